#include "app/cmd_serve.hpp"

#include "app/cli_errors.hpp"
#include "app/live_page.hpp"
#include "app/live_run.hpp"

#include <CLI/CLI.hpp>
#include <chrono>
#include <fmt/format.h>
#include <httplib.h>
#include <iostream>
#include <thread>

namespace gapflow {

struct ServeCommand::Options {
  CLI::App* cmd = nullptr;
  LiveRunDef live;
  std::string model = "2d";
  std::string host = "127.0.0.1";
  int port = 8080;
  double exit_after_s = 0;
};

ServeCommand::ServeCommand(CLI::App& app) : o_(std::make_unique<Options>()) {
  Options& o = *o_;
  o.cmd = app.add_subcommand("serve", "Run a scenario live and steer it from a browser (http://127.0.0.1:8080/)");
  o.cmd->add_option("scenario", o.live.scenario_file, "Scenario file (TOML)")->required();
  o.cmd->add_option("--set", o.live.overrides, "Override one scenario key at start, like `run --set` (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  o.cmd->add_option("--model", o.model, "Model: 2d (Box2D, reduced) or 3d (Bullet, full)")
      ->check(CLI::IsMember({"2d", "3d"}));
  o.cmd->add_option("--port", o.port, "TCP port (default 8080)")->check(CLI::Range(1, 65535));
  o.cmd->add_option("--host", o.host, "Address to bind (default 127.0.0.1: this machine only)");
  o.cmd->add_option("--speed", o.live.speed, "Simulated seconds per wall second at most (default 1: real time)")
      ->check(CLI::PositiveNumber);
  o.cmd->add_option("--exit-after", o.exit_after_s, "Stop serving after this many wall seconds (0 = run until Ctrl-C)")
      ->check(CLI::NonNegativeNumber);
}

ServeCommand::~ServeCommand() = default;

namespace {

int serve(const ServeCommand::Options& o) {
  LiveRunDef def = o.live;
  def.model = parse_model_kind(o.model);
  LiveRun live(def);  // validates the scenario: exit 2 before anything is served

  httplib::Server server;
  server.Get("/", [](const httplib::Request&, httplib::Response& r) { r.set_content(kLivePage, "text/html"); });
  server.Get("/state", [&](const httplib::Request&, httplib::Response& r) {
    r.set_content(live.state_json(), "application/json");
  });
  server.Get("/geometry", [&](const httplib::Request&, httplib::Response& r) {
    r.set_content(live.geometry_json(), "application/json");
  });
  server.Post("/pause", [&](const httplib::Request&, httplib::Response& r) { live.set_paused(true), r.set_content("paused", "text/plain"); });
  server.Post("/resume", [&](const httplib::Request&, httplib::Response& r) { live.set_paused(false), r.set_content("running", "text/plain"); });
  server.Post("/restart", [&](const httplib::Request&, httplib::Response& r) { live.restart(), r.set_content("restarted", "text/plain"); });
  // Body: one `key=value`, validated like --set; the run restarts with it.
  server.Post("/set", [&](const httplib::Request& q, httplib::Response& r) {
    bool restarted = false;
    const std::string error = live.apply(q.body, restarted);
    if (error.empty()) {
      const std::string how = restarted ? " (run restarted from release)" : " (taken up by the running run)";
      std::cerr << "serve: applied " << q.body << how << "\n";
      r.set_content("applied " + q.body + how, "text/plain");
    } else {
      r.status = 400;
      r.set_content("rejected: " + error, "text/plain");
    }
  });

  if (!server.bind_to_port(o.host.c_str(), o.port))
    throw std::runtime_error(fmt::format("cannot listen on {}:{} (in use? try --port)", o.host, o.port));
  std::cerr << fmt::format("serving '{}' ({}) on http://{}:{}/  (Ctrl-C to stop)\n", o.live.scenario_file, o.model,
                           o.host, o.port);
  std::thread stopper;
  if (o.exit_after_s > 0)
    stopper = std::thread([&] {
      std::this_thread::sleep_for(std::chrono::duration<double>(o.exit_after_s));
      server.stop();
    });
  server.listen_after_bind();
  if (stopper.joinable()) stopper.join();
  return 0;
}

}  // namespace

std::optional<int> ServeCommand::run() const {
  if (!o_->cmd->parsed()) return std::nullopt;
  return exit_code_of([&] { return serve(*o_); });
}

}  // namespace gapflow
