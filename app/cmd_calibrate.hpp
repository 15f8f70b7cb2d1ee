// The `gapflow calibrate` and `gapflow twin` subcommands (calibrate/).
//
//   gapflow calibrate DATA.toml [--model 2d|3d] [--jobs N] [--out DIR] [--db PATH] [--no-plots] [--mpi]
//   gapflow twin DATA.toml --out TWIN.toml --truth TRUTH.json [--model 2d|3d] [--seed S]
//                [--effect NAME[:low|:high|=VALUE]]... [--set key=value]... [--replicates N] [--name NAME]
#pragma once

#include <memory>
#include <optional>

namespace CLI {
class App;
}

namespace gapflow {

class CalibrateCommands {
 public:
  explicit CalibrateCommands(CLI::App& app);
  ~CalibrateCommands();
  CalibrateCommands(const CalibrateCommands&) = delete;
  CalibrateCommands& operator=(const CalibrateCommands&) = delete;

  // The exit code when `calibrate` or `twin` was chosen; nullopt otherwise.
  std::optional<int> run() const;

  struct Options;

 private:
  std::unique_ptr<Options> o_;
};

}  // namespace gapflow
