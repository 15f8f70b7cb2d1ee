// The `gapflow serve` subcommand: a live view of one run in a browser.
//
//   gapflow serve SCENARIO.toml [--model 2d|3d] [--set key=value]... [--port 8080] [--host 127.0.0.1]
//
// Runs the scenario in real time (or as fast as the machine allows) and serves a
// page on http://127.0.0.1:PORT/ that draws the board in a canvas from polled
// JSON state, shows t, J, passed, clogs and the real-time factor, and has
// controls to pause, restart and change the obstruction (distance, shape), the gap
// and the shaking. Every change goes through the scenario loader's --set path
// (validated like the file, errors shown on the page) and restarts the run from
// release with the new scenario (the engines compile the geometry once per run);
// a shaking amplitude, frequency, direction or period is taken up by the running run.
//
// Usage in main(): construct ServeCommand on the app before parsing; after
// parsing, `if (auto code = serve_command.run()) return *code;`.
#pragma once

#include <memory>
#include <optional>

namespace CLI {
class App;
}

namespace gapflow {

class ServeCommand {
 public:
  explicit ServeCommand(CLI::App& app);
  ~ServeCommand();
  ServeCommand(const ServeCommand&) = delete;
  ServeCommand& operator=(const ServeCommand&) = delete;

  // The exit code when `serve` was chosen; nullopt otherwise.
  std::optional<int> run() const;

  struct Options;

 private:
  std::unique_ptr<Options> o_;
};

}  // namespace gapflow
