#include "app/live_run.hpp"

#include "common/scenario_loader.hpp"
#include "view/frame.hpp"

#include <chrono>
#include <cmath>
#include <fmt/format.h>

namespace gapflow {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point a) { return std::chrono::duration<double>(Clock::now() - a).count(); }

// Loaded, compiled and checked for the model (check_model_supports), errors located: the
// run thread must never meet a scenario its model refuses.
CompiledScenario compile_with(const std::string& file, const std::vector<std::string>& overrides, ModelKind model) {
  LoadedScenario loaded = load_scenario(file, overrides);
  try {
    CompiledScenario sc = compile_scenario(loaded.def);
    check_model_supports(sc, model);
    return sc;
  } catch (const ScenarioInvalid& e) {
    throw locate(e, loaded);
  }
}

std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o.append({'\\', c});
    else if (static_cast<unsigned char>(c) < 0x20) o += fmt::format("\\u{:04x}", c);
    else o += c;
  }
  return o + "\"";
}

std::string xy_mm(Vec2 p) { return fmt::format("[{:.2f},{:.2f}]", p.x * 1e3, p.y * 1e3); }

std::string polygon_json(const ConvexPolygon& p) {
  std::string o = "[";
  for (size_t i = 0; i < p.vertices.size(); ++i) {
    if (i) o += ',';
    o += xy_mm(p.vertices[i]);
  }
  return o + "]";
}

std::string geometry_of(const CompiledScenario& sc, ModelKind model, const std::vector<std::string>& overrides) {
  const ObstructionGeometry& ob = sc.obstruction;
  std::string obstruction = "null";
  if (ob.shape == ObstructionShape::cylinder)
    obstruction = fmt::format("{{\"c\":{},\"r\":{:.2f}}}", xy_mm(ob.circle.centre), ob.circle.radius * 1e3);
  else if (ob.shape != ObstructionShape::none)
    obstruction = fmt::format("{{\"v\":{}}}", polygon_json(ob.polygon));
  const ScenarioDef& d = sc.def;
  const std::string shape = d.obstruction.preset.empty() ? to_string(d.obstruction.shape) : d.obstruction.preset;
  std::string ov = "[";
  for (size_t i = 0; i < overrides.size(); ++i) {
    if (i) ov += ',';
    ov += json_string(overrides[i]);
  }
  ov += "]";
  return fmt::format(
      "{{\"name\":{},\"model\":\"{}\",\"width_mm\":{:.2f},\"length_mm\":{:.2f},\"wall_mm\":{:.2f},\"d_mm\":{:.3f},"
      "\"walls\":[{},{},{},{},{}],\"obstruction\":{},\"tips\":[{},{}],"
      "\"settings\":{{\"obstruction.shape\":{},\"obstruction.distance_mm\":{},\"bottleneck.gap_mm\":{},"
      "\"shaking.walls.enabled\":{},\"shaking.walls.amplitude_mm\":{},\"shaking.obstruction.enabled\":{},"
      "\"shaking.obstruction.amplitude_mm\":{}}},\"overrides\":{}}}",
      json_string(d.name), to_string(model), sc.channel_width * 1e3, sc.plane_length * 1e3, sc.wall_thickness * 1e3,
      sc.nominal_diameter * 1e3, polygon_json(sc.left_bottleneck_wall), polygon_json(sc.right_bottleneck_wall),
      polygon_json(sc.left_retaining_wall), polygon_json(sc.right_retaining_wall), polygon_json(sc.top_wall),
      obstruction, xy_mm(sc.left_tip), xy_mm(sc.right_tip), json_string(shape), d.obstruction.distance_mm,
      d.bottleneck.gap_mm, d.shaking.walls.enabled, d.shaking.walls.amplitude_mm, d.shaking.obstruction.enabled,
      d.shaking.obstruction.amplitude_mm, ov);
}

// The packing as released (shown while the engine settles it against the barrier).
std::string seed_particles_json(const CompiledScenario& sc) {
  std::string p;
  for (const ParticleSeed& s : sc.particles)
    fmt::format_to(std::back_inserter(p), "{}{:.1f},{:.1f},{:.2f},0,0", p.empty() ? "" : ",", s.position.x * 1e3,
                   s.position.y * 1e3, s.diameter * 0.5e3);
  return p;
}

std::string key_of(const std::string& assignment) { return assignment.substr(0, assignment.find('=')); }

}  // namespace

LiveRun::LiveRun(LiveRunDef def) : def_(std::move(def)) {
  const CompiledScenario sc = compile_with(def_.scenario_file, def_.overrides, def_.model);  // bad input: exit 2 before serving
  overrides_ = def_.overrides;
  geometry_ = geometry_of(sc, def_.model, overrides_);
  state_ = "\"t\":0";
  thread_ = std::thread([this] { loop(); });
}

LiveRun::~LiveRun() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    cancel_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

std::string LiveRun::state_json() const {
  std::lock_guard lock(mutex_);
  return fmt::format("{{\"generation\":{},\"paused\":{},{}}}", generation_, paused_, state_);
}

std::string LiveRun::geometry_json() const {
  std::lock_guard lock(mutex_);
  return geometry_;
}

void LiveRun::set_paused(bool paused) {
  {
    std::lock_guard lock(mutex_);
    paused_ = paused;
  }
  wake_.notify_all();
}

void LiveRun::restart() {
  {
    std::lock_guard lock(mutex_);
    ++generation_;
    cancel_ = true;
  }
  wake_.notify_all();
}

std::string LiveRun::apply(const std::string& assignment, bool& restarted) {
  std::vector<std::string> next;
  {
    std::lock_guard lock(mutex_);
    next = overrides_;
  }
  std::erase_if(next, [&](const std::string& o) { return key_of(o) == key_of(assignment); });
  next.push_back(assignment);
  std::optional<CompiledScenario> sc;
  try {
    sc = compile_with(def_.scenario_file, next, def_.model);
  } catch (const ScenarioError& e) {
    return e.what();
  }
  {
    std::lock_guard lock(mutex_);
    overrides_ = next;
    const ShakingDef& now = running_shaking_;
    const bool live = assignment.starts_with("shaking.") && sc->def.shaking.walls.enabled == now.walls.enabled &&
                      sc->def.shaking.obstruction.enabled == now.obstruction.enabled;
    restarted = !live;
    if (live) {
      running_shaking_ = sc->def.shaking;
      shaking_ = sc->def.shaking;  // the running run takes it at its next step
      geometry_ = geometry_of(*sc, def_.model, overrides_);
    } else {
      ++generation_;
      cancel_ = true;
    }
  }
  wake_.notify_all();
  return "";
}

void LiveRun::loop() {
  for (;;) {
    std::vector<std::string> overrides;
    int generation;
    {
      std::lock_guard lock(mutex_);
      if (stopping_) return;
      overrides = overrides_;
      generation = generation_;
      cancel_ = false;
      shaking_.reset();
    }
    CompiledScenario sc = compile_with(def_.scenario_file, overrides, def_.model);  // validated when applied
    {
      std::lock_guard lock(mutex_);
      running_shaking_ = sc.def.shaking;
      geometry_ = geometry_of(sc, def_.model, overrides);
      state_ = "\"phase\":\"settling\",\"t\":0,\"p\":[" + seed_particles_json(sc) + "]";
    }
    try {
      run_once(sc);
    } catch (const RunCancelled&) {
      continue;
    }
    std::unique_lock lock(mutex_);
    state_ = "\"phase\":\"finished\"," + state_.substr(state_.find(',') + 1);
    wake_.wait(lock, [&] { return stopping_ || generation_ != generation; });
  }
}

// `sc` is the run's own copy: a shaking change is written into it between two steps,
// on this thread, and the driver and the monitor read the schedule from it.
void LiveRun::run_once(CompiledScenario& sc) {
  auto session = make_session(sc, def_.model);
  Clock::time_point start;
  double paused_s = 0, last_publish = -1, last_t = 0, last_wall = 0;
  bool started = false, was_stopped = false;
  int clogs = 0;
  StepObserver observer;
  observer.after_step = [&](double t, const EngineSession& s, const GapMonitor& m) {
    if (!started) start = Clock::now(), started = true;  // after settling
    const bool stopped = flow_stopped(sc, m, t);
    clogs += stopped && !was_stopped;
    was_stopped = stopped;
    {
      std::unique_lock lock(mutex_);
      const auto pause_start = Clock::now();
      while (paused_ && !cancel_) wake_.wait_for(lock, std::chrono::milliseconds(100));
      paused_s += seconds_since(pause_start);
      if (shaking_) sc.def.shaking = *shaking_, shaking_.reset();
    }
    const double wall = seconds_since(start) - paused_s;
    if (t > wall * def_.speed)
      std::this_thread::sleep_for(std::chrono::duration<double>(t / def_.speed - wall));
    if (wall - last_publish >= 1 / def_.publish_hz) {
      const double rtf = wall > last_wall ? (t - last_t) / (wall - last_wall) : 0;
      std::vector<ParticleMotion> scratch;
      const FrameState f = capture_frame(sc, s, m, t, clogs, scratch);
      std::string p;
      p.reserve(f.particles.size() * 28);
      for (const ParticleView& v : f.particles)
        fmt::format_to(std::back_inserter(p), "{}{:.1f},{:.1f},{:.2f},{:.0f},{}", p.empty() ? "" : ",", v.x * 1e3,
                       v.y * 1e3, v.radius * 1e3, v.speed() * 1e3, static_cast<int>(v.state));
      std::string body = fmt::format(
          "\"phase\":\"running\",\"t\":{:.3f},\"passed\":{},\"clogs\":{},\"clogged\":{},\"on_obstruction\":{},"
          "\"J\":{:.2f},\"rtf\":{:.3f},\"offsets\":{{\"lw\":{},\"rw\":{},\"ob\":{}}},\"p\":[{}]",
          t, f.passed, f.clogs, f.clogged, f.arch_on_obstruction, f.j_so_far(), rtf, xy_mm(f.offsets.left_wall),
          xy_mm(f.offsets.right_wall), xy_mm(f.offsets.obstruction), p);
      std::lock_guard lock(mutex_);
      state_ = std::move(body);
      last_publish = wall, last_t = t, last_wall = wall;
    }
  };
  run_simulation(sc, *session, &observer, &cancel_);
}

}  // namespace gapflow
