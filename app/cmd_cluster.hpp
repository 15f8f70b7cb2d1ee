// The cluster subcommands (README "Running a study on a cluster"):
//
//   gapflow merge OUT.sqlite SHARD.sqlite...   merge shard stores by job key (studies/merge.hpp)
//   gapflow compare A.sqlite B.sqlite          run by run: are two stores the same runs?
//   gapflow slurm STUDY.toml [--array-size K] [--time T] [--partition P] [--cpus-per-task C] [--out DIR]
//                                              write an sbatch job array + a dependent merge-and-report job
//
// Exit codes: 0 success; 1 conflicts, missing jobs or differing stores; 2 bad input.
#pragma once

#include <memory>
#include <optional>

namespace CLI {
class App;
}

namespace gapflow {

class ClusterCommands {
 public:
  explicit ClusterCommands(CLI::App& app);
  ~ClusterCommands();
  ClusterCommands(const ClusterCommands&) = delete;
  ClusterCommands& operator=(const ClusterCommands&) = delete;

  // The exit code when one of these subcommands was chosen; nullopt otherwise.
  std::optional<int> run() const;

  struct Options;  // the parsed command line (bound by address into CLI11)

 private:
  std::unique_ptr<Options> o_;
};

}  // namespace gapflow
