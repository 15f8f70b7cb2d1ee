// The `gapflow run` options that make pictures and files of the run
// (view/run_outputs.hpp): --snapshot-at, --snapshot-dir, --snapshot-on-clog,
// --colour, --px-per-mm, --speed-max, --movie, --fps, --vtk, --vtk-interval.
#pragma once

#include "view/run_outputs.hpp"

#include <string>

namespace CLI {
class App;
}

namespace gapflow {

struct RunOutputOptions {
  RunOutputDef def;
  std::string colour = "speed";  // "speed" | "state"
  // The definition with the colouring parsed; throws std::invalid_argument (exit 2).
  RunOutputDef resolved() const;
};

void add_run_output_options(CLI::App* cmd, RunOutputOptions& o);

}  // namespace gapflow
