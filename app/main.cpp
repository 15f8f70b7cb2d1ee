// gapflow: the command line.
//   gapflow run SCENARIO.toml [--model 2d|3d] [--set key=value]... [--out record.json]
//   gapflow check SCENARIO.toml [--set key=value]... [--print]
// Exit codes: 0 success, 2 bad input (scenario or command line), 1 failure while running.
#include "app/models.hpp"
#include "common/geometry.hpp"
#include "common/scenario_loader.hpp"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <iostream>

namespace {

using namespace gapflow;

constexpr int kBadInput = 2;
constexpr int kFailure = 1;

struct ScenarioArgs {
  std::string file;
  std::vector<std::string> overrides;
};

void add_scenario_args(CLI::App* cmd, ScenarioArgs& a) {
  cmd->add_option("scenario", a.file, "Scenario file (TOML), e.g. scenarios/paper/no_obstruction_medium.toml")
      ->required();
  cmd->add_option("--set", a.overrides,
                  "Override one scenario key, validated like the file, e.g. --set obstruction.distance_mm=20 "
                  "(repeatable)")
      ->take_all()
      ->allow_extra_args(false);
}

// Load, validate and compile; errors carry file:line:column and the key.
CompiledScenario load_and_compile(const ScenarioArgs& a) {
  LoadedScenario loaded = load_scenario(a.file, a.overrides);
  try {
    return compile_scenario(loaded.def);
  } catch (const ScenarioInvalid& e) {
    throw locate(e, loaded);
  }
}

// Write to a temporary name and rename when complete: a reader never sees half a file.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const std::string tmp = path + ".partial";
  {
    std::ofstream out(tmp);
    if (!out) throw std::runtime_error("cannot write " + tmp);
    write(out);
    if (!out.flush()) throw std::runtime_error("error while writing " + tmp);
  }
  std::filesystem::rename(tmp, path);
}

int cmd_run(const ScenarioArgs& a, const std::string& model_name, const std::string& out_path, bool quiet) {
  const ModelKind kind = parse_model_kind(model_name);
  const CompiledScenario sc = load_and_compile(a);
  if (!quiet)
    std::cerr << fmt::format("running '{}' in {} with {} particles...\n", sc.def.name, to_string(kind),
                             sc.particles.size());
  const RunRecord record = run_model(sc, kind);
  write_summary(std::cout, record);
  if (!out_path.empty()) write_file_atomically(out_path, [&](std::ostream& o) { write_json(o, record); });
  return 0;
}

int cmd_check(const ScenarioArgs& a, bool print) {
  const CompiledScenario sc = load_and_compile(a);
  if (print) std::cout << canonical_toml(sc.def);
  std::cerr << fmt::format("{}: ok ('{}', {} particles, W/d = {:.3f}, hash {:016x})\n", a.file, sc.def.name,
                           sc.particles.size(), sc.w_over_d(), sc.scenario_hash);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "gapflow: granular flow through a bottleneck with obstructions.\n"
      "Spheres roll down an inclined board into a bottleneck and out through a gap W; an obstruction at\n"
      "distance D from the gap can raise the flow rate J. One scenario file drives a fast 2D model (Box2D)\n"
      "and a full 3D model (Bullet). Start with:\n"
      "  gapflow run scenarios/paper/no_obstruction_medium.toml\n"
      "  gapflow check scenarios/paper/cylinder.toml --set obstruction.distance_mm=90\n"};
  app.require_subcommand(1);

  ScenarioArgs run_args;
  std::string model = "2d", out_path;
  bool quiet = false;
  CLI::App* run = app.add_subcommand("run", "Run one simulation and print J, clogs and timing");
  add_scenario_args(run, run_args);
  run->add_option("--model", model, "Model: 2d (Box2D, reduced) or 3d (Bullet, full)")
      ->check(CLI::IsMember({"2d", "3d"}));
  run->add_option("--out", out_path, "Write the complete run record (crossings, avalanches, clogs) as JSON");
  run->add_flag("--quiet", quiet, "Do not print progress to stderr");

  ScenarioArgs check_args;
  bool print = false;
  CLI::App* check = app.add_subcommand("check", "Validate a scenario (and its --set overrides) without running");
  add_scenario_args(check, check_args);
  check->add_flag("--print", print, "Print the complete resolved scenario as canonical TOML");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kBadInput;
  }

  try {
    if (*run) return cmd_run(run_args, model, out_path, quiet);
    if (*check) return cmd_check(check_args, print);
  } catch (const ScenarioError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kBadInput;
  } catch (const std::invalid_argument& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kBadInput;
  } catch (const std::exception& e) {
    std::cerr << "gapflow failed: " << e.what() << "\n";
    return kFailure;
  }
  return 0;
}
