#include "app/cmd_cluster.hpp"

#include "app/cli_errors.hpp"
#include "common/text_file.hpp"
#include "studies/jobs.hpp"
#include "studies/merge.hpp"
#include "studies/store.hpp"
#include "studies/study.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iostream>

namespace gapflow {

namespace fs = std::filesystem;

struct ClusterCommands::Options {
  CLI::App* merge = nullptr;
  std::string out;
  std::vector<std::string> sources;

  CLI::App* compare = nullptr;
  std::string first, second;

  CLI::App* slurm = nullptr;
  std::string study_file, time, partition, dir;
  int array_size = 0, cpus = 1;
  bool quick = false;
};

namespace {

int cmd_merge(const ClusterCommands::Options& o) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<fs::path> sources(o.sources.begin(), o.sources.end());
  for (const auto& s : sources)  // checked before OUT is created
    if (!fs::is_regular_file(s)) throw std::invalid_argument("merge: no results store at " + s.string());
  Store out(o.out, StoreAccess::exclusive);
  const MergeSummary m = merge_stores(out, sources);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << fmt::format("merged {} stores into {} in {:.2f} s: {} runs added, {} already there (identical), "
                           "{} conflicts; {} runs in the store\n",
                           sources.size(), o.out, seconds, m.added, m.identical, m.conflicts.size(), out.count());
  for (const MergeConflict& c : m.conflicts)
    std::cout << fmt::format("  conflict {} from {}: {} (kept the run already in {})\n", c.key, c.source.string(),
                             c.what, o.out);
  if (m.planned > 0)
    std::cout << fmt::format("plan: {} jobs, {} stored, {} missing\n", m.planned, m.planned - m.missing.size(),
                             m.missing.size());
  else
    std::cout << "plan: none recorded in these stores (not run with --shard), so missing jobs cannot be listed\n";
  for (const PlannedJob& p : m.missing)
    std::cout << fmt::format("  missing {} (share {}): {} '{}' {} r{}\n", p.id.key, p.shard, p.id.series,
                             p.id.point_label, p.id.model, p.id.replicate);
  if (!m.missing.empty())
    std::cout << "incomplete: run the shares named above again (each resumes its store), then merge again\n";
  return m.conflicts.empty() && m.missing.empty() ? 0 : kExitFailure;
}

int cmd_compare(const ClusterCommands::Options& o) {
  for (const auto& f : {o.first, o.second})
    if (!fs::is_regular_file(f)) throw std::invalid_argument("compare: no results store at " + f);
  const Store a(o.first, StoreAccess::read), b(o.second, StoreAccess::read);
  const std::vector<std::string> differences = compare_stores(a, b);
  for (const std::string& d : differences) std::cout << d << "\n";
  std::cout << fmt::format("{} and {}: {} runs and {} runs, {}\n", o.first, o.second, a.count(), b.count(),
                           differences.empty() ? "identical run by run (wall times aside)"
                                               : fmt::format("{} differences", differences.size()));
  return differences.empty() ? 0 : kExitFailure;
}

constexpr const char* kOurs = "# written by gapflow slurm";

// Never overwrite a file we did not write: our scripts carry kOurs on their second line.
void write_script(const fs::path& path, const std::string& text) {
  if (fs::exists(path)) {
    std::ifstream in(path);
    std::string shebang, mark;
    std::getline(in, shebang);
    std::getline(in, mark);
    if (mark.rfind(kOurs, 0) != 0)
      throw std::invalid_argument(fmt::format("slurm: {} exists and was not written by gapflow slurm: move it away "
                                              "or choose another --out",
                                              path.string()));
  }
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
  fs::permissions(path, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add);
}

std::string sbatch_header(const ClusterCommands::Options& o, const std::string& name, const fs::path& log) {
  std::string h = fmt::format("#SBATCH --job-name={}\n#SBATCH --output={}\n", name, log.string());
  if (!o.time.empty()) h += fmt::format("#SBATCH --time={}\n", o.time);
  if (!o.partition.empty()) h += fmt::format("#SBATCH --partition={}\n", o.partition);
  return h;
}

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

int cmd_slurm(const ClusterCommands::Options& o) {
  StudyDef study = load_study(o.study_file);
  if (o.quick && !study.quick.present)
    throw std::invalid_argument("slurm --quick: this study has no [quick] table");
  if (o.quick) study = apply_quick(std::move(study));
  const std::size_t n_jobs = expand_jobs(study).size();  // validates every scenario before anything is written
  const int k = std::clamp<int>(o.array_size > 0 ? o.array_size : 32, 1, static_cast<int>(std::max<std::size_t>(1, n_jobs)));
  const std::string name = o.quick ? study.name + "-quick" : study.name;
  const fs::path results = fs::absolute(fs::path("results") / name);
  const fs::path dir = o.dir.empty() ? results / "slurm" : fs::absolute(o.dir);
  const fs::path shards = results / "shards", merged = results / "runs.sqlite";
  const fs::path gapflow = fs::canonical("/proc/self/exe"), study_file = fs::absolute(o.study_file);
  fs::create_directories(dir / "logs");
  const std::string quick = o.quick ? " --quick" : "";

  const fs::path array = dir / "array.sbatch", merge = dir / "merge.sbatch", submit = dir / "submit.sh";
  write_script(array, fmt::format(
      "#!/bin/bash\n{}: study '{}', {} jobs in {} shares, one per array task. Resubmit to resume:\n"
      "# each share's store keeps its finished runs.\n"
      "{}#SBATCH --array=1-{}\n#SBATCH --cpus-per-task={}\n"
      "set -euo pipefail\n"
      "share=${{SLURM_ARRAY_TASK_ID}}\n"
      "exec {} study {}{} --shard \"$share/{}\" --jobs \"${{SLURM_CPUS_PER_TASK:-1}}\" \\\n"
      "  --db {}/\"shard-$share-of-{}.sqlite\"\n",
      kOurs, study.name, n_jobs, k, sbatch_header(o, "gapflow-" + name, dir / "logs" / "share-%a.log"), k, o.cpus,
      quoted(gapflow), quoted(study_file), quick, k, quoted(shards), k));
  write_script(merge, fmt::format(
      "#!/bin/bash\n{}: merge the {} shares of study '{}' and write its report (runs after the array,\n"
      "# however its tasks ended: the merge lists any missing job).\n"
      "{}set -uo pipefail\n"
      "stores=()\n"
      "for i in $(seq 1 {}); do\n"
      "  f={}/\"shard-$i-of-{}.sqlite\"\n"
      "  if [ -f \"$f\" ]; then stores+=(\"$f\"); else echo \"share $i/{} left no store\"; fi\n"
      "done\n"
      "[ ${{#stores[@]}} -gt 0 ] || {{ echo 'no share left a store'; exit 1; }}\n"
      "{} merge {} \"${{stores[@]}}\" || exit $?\n"
      "exec {} report {}\n",
      kOurs, k, study.name, sbatch_header(o, "gapflow-" + name + "-merge", dir / "logs" / "merge.log"), k,
      quoted(shards), k, k, quoted(gapflow), quoted(merged), quoted(gapflow), quoted(results)));
  write_script(submit, fmt::format(
      "#!/bin/sh\n{}: submit the array, then the merge once every task has ended.\n"
      "set -e\n"
      "array=$(sbatch --parsable {})\n"
      "array=${{array%%;*}}\n"
      "merge=$(sbatch --parsable --dependency=afterany:$array {})\n"
      "echo \"submitted array job $array ({} tasks) and merge job ${{merge%%;*}}\"\n",
      kOurs, quoted(array), quoted(merge), k));
  std::cout << fmt::format("study '{}': {} jobs in {} shares (balanced by expected cost); scripts in {}\n"
                           "submit with:\n  sh {}\nor by hand:\n  sbatch {}   # prints the array's job id, JOBID\n"
                           "  sbatch --dependency=afterany:JOBID {}\n"
                           "shares write {}/shard-I-of-{}.sqlite; the merge writes {} and the report beside it.\n"
                           "Progress: gapflow study {}{} --shard I/{} --db {}/shard-I-of-{}.sqlite --status\n",
                           study.name, n_jobs, k, dir.string(), submit.string(), array.string(), merge.string(),
                           shards.string(), k, merged.string(), study_file.string(), quick, k, shards.string(), k);
  return 0;
}

}  // namespace

ClusterCommands::ClusterCommands(CLI::App& app) : o_(std::make_unique<Options>()) {
  Options& o = *o_;
  o.merge = app.add_subcommand("merge", "Merge the stores of a sharded study by job key (idempotent; conflicts and "
                                        "missing jobs are listed, exit 1)");
  o.merge->add_option("out", o.out, "Output store (created when missing), e.g. results/tiny/runs.sqlite")->required();
  o.merge->add_option("shards", o.sources, "Shard stores to merge in")->required();

  o.compare = app.add_subcommand("compare", "Compare two stores run by run (exit 1 when they differ)");
  o.compare->add_option("first", o.first, "A results store")->required();
  o.compare->add_option("second", o.second, "Another results store")->required();

  o.slurm = app.add_subcommand("slurm", "Write sbatch scripts that run a study as a Slurm job array and merge it");
  o.slurm->add_option("study", o.study_file, "Study file (TOML)")->required();
  o.slurm->add_option("--array-size", o.array_size, "Array tasks = shares (default 32, at most the job count)")
      ->check(CLI::Range(1, 100000));
  o.slurm->add_option("--time", o.time, "Time limit of each task, as sbatch --time (e.g. 02:00:00)");
  o.slurm->add_option("--partition", o.partition, "Slurm partition");
  o.slurm->add_option("--cpus-per-task", o.cpus, "Cores per task (its worker threads)")->check(CLI::Range(1, 1024));
  o.slurm->add_option("--out", o.dir, "Folder of the scripts (default results/<name>/slurm)");
  o.slurm->add_flag("--quick", o.quick, "The study's [quick] variant (its own results/<name>-quick folder)");
}

ClusterCommands::~ClusterCommands() = default;

std::optional<int> ClusterCommands::run() const {
  if (o_->merge->parsed()) return exit_code_of([&] { return cmd_merge(*o_); });
  if (o_->compare->parsed()) return exit_code_of([&] { return cmd_compare(*o_); });
  if (o_->slurm->parsed()) return exit_code_of([&] { return cmd_slurm(*o_); });
  return std::nullopt;
}

}  // namespace gapflow
