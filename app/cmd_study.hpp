// The `gapflow study` and `gapflow export` subcommands.
//
//   gapflow study STUDY.toml [--quick] [--jobs N] [--db PATH] [--dry-run]
//                            [--plan [--shards K]] [--shard I/K] [--status] [--mpi]
//   gapflow export DB --table runs|crossings|avalanches|clogs [--csv OUT.csv]
//
// Usage in main(): construct StudyCommands on the app before parsing; after
// parsing, `if (auto code = study_commands.run()) return *code;`. run() reports
// its own errors (exit 2 bad input, 1 failure, 130 interrupted).
#pragma once

#include <memory>
#include <optional>

namespace CLI {
class App;
}

namespace gapflow {

class StudyCommands {
 public:
  explicit StudyCommands(CLI::App& app);
  ~StudyCommands();
  StudyCommands(const StudyCommands&) = delete;
  StudyCommands& operator=(const StudyCommands&) = delete;

  // The exit code when `study` or `export` was chosen; nullopt otherwise.
  std::optional<int> run() const;

  struct Options;  // the parsed command line (bound by address into CLI11)

 private:
  std::unique_ptr<Options> o_;
};

}  // namespace gapflow
