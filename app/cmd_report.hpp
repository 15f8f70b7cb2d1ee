// The `gapflow report` subcommand.
//
//   gapflow report RESULTS [--study STUDY.toml] [--out DIR] [--no-plots] [--no-snapshots] [--pairing]
//
// RESULTS is a study's results store (runs.sqlite) or its folder. Writes
// points.csv, plots (PNG, via studies/plot_study.py) and report.md into DIR
// (default: the store's folder) and prints the tables; unless --no-snapshots, one
// re-simulated top view per point class (studies/report_snapshots.hpp). The study file is
// optional; its [report] table picks the experiment analysis
// (studies/report.hpp). --pairing prints J/J_0 paired by replicate against unpaired per point
// (studies/paired.hpp) and writes nothing.
//
// Usage in main(): construct ReportCommand on the app before parsing; after
// parsing, `if (auto code = report_command.run()) return *code;`. run() reports
// its own errors (exit 2 bad input, 1 failure).
#pragma once

#include <memory>
#include <optional>

namespace CLI {
class App;
}

namespace gapflow {

class ReportCommand {
 public:
  explicit ReportCommand(CLI::App& app);
  ~ReportCommand();
  ReportCommand(const ReportCommand&) = delete;
  ReportCommand& operator=(const ReportCommand&) = delete;

  // The exit code when `report` was chosen; nullopt otherwise.
  std::optional<int> run() const;

  struct Options;  // the parsed command line (bound by address into CLI11)

 private:
  std::unique_ptr<Options> o_;
};

}  // namespace gapflow
