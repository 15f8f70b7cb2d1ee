#include "app/cmd_report.hpp"

#include "app/cli_errors.hpp"

#include "common/scenario_loader.hpp"
#include "studies/paired.hpp"
#include "studies/report.hpp"

#include <CLI/CLI.hpp>

#include <iostream>

namespace gapflow {

struct ReportCommand::Options {
  CLI::App* cmd = nullptr;
  std::string results, study, out;
  bool no_plots = false;
  bool no_snapshots = false;
  bool quick = false;
  bool pairing = false;
  std::string compare;
  std::string j;
};

namespace {


int cmd_report(const ReportCommand::Options& o) {
  ReportRequest r;
  r.results = o.results;
  if (!o.study.empty()) r.study = o.study;
  if (!o.out.empty()) r.out = o.out;
  r.plots = !o.no_plots;
  r.snapshots = !o.no_snapshots;
  r.quick = o.quick;
  if (!o.compare.empty()) {
    const std::size_t eq = o.compare.find('=');
    const std::string model = o.compare.substr(0, eq);
    if (eq == std::string::npos || (model != "2d" && model != "3d") || eq + 1 == o.compare.size())
      throw std::invalid_argument("--compare '" + o.compare + "': expected MODEL=STORE with MODEL 2d or 3d, e.g. 3d=results/flow-vs-distance");
    r.compare = ReportRequest::Compare{model, o.compare.substr(eq + 1)};
  }
  if (!o.j.empty()) r.j = jkind_from_option(o.j);
  if (o.pairing && r.compare) throw std::invalid_argument("--pairing compares runs of one store: drop --compare");
  if (o.pairing) {  // a measurement printed, no file written
    const ReportData data = load_report_data(r, std::cerr);
    if (data.study.report.baseline.empty()) throw std::invalid_argument("--pairing: the study has no [report] baseline");
    std::cout << render_text(pairing_table(pairing_rows(data, data.study.report.j), data.study.report.j));
    return 0;
  }
  make_report(r, std::cout, std::cerr);
  return 0;
}

}  // namespace

ReportCommand::ReportCommand(CLI::App& app) : o_(std::make_unique<Options>()) {
  Options& o = *o_;
  o.cmd = app.add_subcommand("report",
                             "Analyse a study's results store: "
                             "points.csv, tables, plots and report.md");
  o.cmd->add_option("results", o.results, "Results store (runs.sqlite) or its folder, e.g. results/tiny/")->required();
  o.cmd->add_option("--study", o.study,
                    "Study file (TOML): description, and the [report] table (analysis kind, "
                    "baseline, J kind)");
  o.cmd->add_option("--out", o.out, "Output folder (default: the store's folder)");
  o.cmd->add_flag("--no-plots", o.no_plots, "Do not call Python for the PNG plots");
  o.cmd->add_flag("--pairing", o.pairing,
                  "Print J/J_0 per point paired by replicate against unpaired (correlation, interval widths) "
                  "and exit; writes nothing (studies/paired.hpp)");
  o.cmd->add_option("--compare", o.compare,
                    "MODEL=STORE: that model's runs from another study's store join the report (same series and "
                    "points), e.g. --compare 3d=results/flow-vs-distance for a 2D-only re-run");
  o.cmd->add_option("--j", o.j, "Flow rate for the analyses instead of the study's [report] j: paper, flowing or mid")
      ->check(CLI::IsMember(jkind_option_names()));
  o.cmd->add_flag("--no-snapshots", o.no_snapshots,
                  "Do not re-simulate one stored run per point class for the report's top-view snapshots");
  o.cmd->add_flag("--quick", o.quick,
                  "The store holds the study's --quick variant: a screen's thinned grid, the snapshots' jobs "
                  "(the study file must have a [quick] table)");
}

ReportCommand::~ReportCommand() = default;

std::optional<int> ReportCommand::run() const {
  if (!o_->cmd->parsed()) return std::nullopt;
  return exit_code_of([&] { return cmd_report(*o_); });
}

}  // namespace gapflow
