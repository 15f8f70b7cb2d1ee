#include "view/run_outputs.hpp"

#include "common/text_file.hpp"
#include "view/movie.hpp"
#include "view/vtk_series.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <optional>
#include <stdexcept>

namespace gapflow {

void RunOutputDef::validate() const {
  for (double t : snapshot_times_s)
    if (!(t >= 0) || !std::isfinite(t))
      throw std::invalid_argument(fmt::format("--snapshot-at: {} s is not a time >= 0 after release", t));
  if (!movie_path.empty()) {
    if (!(movie_fps > 0 && movie_fps <= 240)) throw std::invalid_argument(fmt::format("--fps = {} is not in (0, 240]", movie_fps));
    require_ffmpeg();
  }
  if (!vtk_dir.empty() && !(vtk_interval_s > 0))
    throw std::invalid_argument(fmt::format("--vtk-interval = {} s must be > 0", vtk_interval_s));
  if (!(view.speed_max_m_s > 0)) throw std::invalid_argument("--speed-max must be > 0 m/s");
}

struct RunOutputs::Writers {
  std::unique_ptr<TopView> view;        // snapshots and movie
  std::unique_ptr<TopView> state_view;  // clog snapshots (coloured by state)
  std::unique_ptr<MovieEncoder> movie;
  std::unique_ptr<VtkSeries> vtk;
  std::vector<double> snapshot_times;  // sorted, s
  size_t next_snapshot = 0;
  long next_movie_frame = 0;
  long next_vtk_frame = 0;
  bool was_stopped = false;
  int clogs = 0;
  double t_last = 0;
  std::vector<std::string> written;
  std::optional<FrameState> frame;  // this step's, captured once when some output needs it
  std::vector<ParticleMotion> scratch;
};

RunOutputs::RunOutputs(const CompiledScenario& sc, RunOutputDef def)
    : sc_(sc), def_(std::move(def)), w_(std::make_unique<Writers>()) {
  def_.validate();
  // Every target checked before anything is drawn or simulated (exit 2, nothing written).
  if (!def_.movie_path.empty()) check_output_file(def_.movie_path);  // absent or a regular file: /dev/null is not
  if (!def_.snapshot_times_s.empty() || def_.snapshot_on_clog) check_output_folder(def_.snapshot_dir);
  if (!def_.vtk_dir.empty()) check_output_folder(def_.vtk_dir);
  Writers& w = *w_;
  if (!def_.snapshot_times_s.empty() || !def_.movie_path.empty()) w.view = std::make_unique<TopView>(sc, def_.view);
  if (def_.snapshot_on_clog) {
    TopViewDef state = def_.view;
    state.colour_by = Colouring::state;
    w.state_view = std::make_unique<TopView>(sc, state);
  }
  if (!def_.snapshot_times_s.empty() || def_.snapshot_on_clog) std::filesystem::create_directories(def_.snapshot_dir);
  w.snapshot_times = def_.snapshot_times_s;
  std::sort(w.snapshot_times.begin(), w.snapshot_times.end());
  if (!def_.movie_path.empty())
    w.movie = std::make_unique<MovieEncoder>(def_.movie_path, w.view->width(), w.view->height(), def_.movie_fps);
  if (!def_.vtk_dir.empty()) w.vtk = std::make_unique<VtkSeries>(sc, def_.vtk_dir);
  observer_.after_step = [this](double t, const EngineSession& s, const GapMonitor& m) { after_step(t, s, m); };
}

RunOutputs::~RunOutputs() = default;

const FrameState& RunOutputs::frame(double t, const EngineSession& session, const GapMonitor& monitor) {
  if (!w_->frame) w_->frame = capture_frame(sc_, session, monitor, t, w_->clogs, w_->scratch);
  return *w_->frame;
}

void RunOutputs::after_step(double t, const EngineSession& session, const GapMonitor& monitor) {
  Writers& w = *w_;
  w.frame.reset();
  w.t_last = t;
  const double half_step = session.time_step() / 2;  // a frame due at T is drawn at the step nearest T
  const bool stopped = flow_stopped(sc_, monitor, t);
  if (stopped && !w.was_stopped) {
    ++w.clogs;
    if (w.state_view) {
      w.state_view->draw(frame(t, session, monitor));
      const std::string path = (std::filesystem::path(def_.snapshot_dir) / fmt::format("clog{:03d}_t{:07.2f}s.png", w.clogs, t)).string();
      w.state_view->write_png(path);
      w.written.push_back(path);
    }
  }
  w.was_stopped = stopped;

  bool drawn = false;
  while (w.next_snapshot < w.snapshot_times.size() && t + half_step >= w.snapshot_times[w.next_snapshot]) {
    if (!drawn) w.view->draw(frame(t, session, monitor)), drawn = true;
    const std::string path =
        (std::filesystem::path(def_.snapshot_dir) / fmt::format("t{:07.2f}s.png", w.snapshot_times[w.next_snapshot])).string();
    w.view->write_png(path);
    w.written.push_back(path);
    ++w.next_snapshot;
  }
  if (w.movie && t + half_step >= w.next_movie_frame / def_.movie_fps) {
    if (!drawn) w.view->draw(frame(t, session, monitor)), drawn = true;
    w.movie->add_frame(w.view->data(), w.view->stride());
    ++w.next_movie_frame;
  }
  if (w.vtk && t + half_step >= w.next_vtk_frame * def_.vtk_interval_s) {
    w.vtk->write(frame(t, session, monitor));
    ++w.next_vtk_frame;
  }
}

const std::vector<std::string>& RunOutputs::written() const { return w_->written; }

std::vector<std::string> RunOutputs::finish() {
  Writers& w = *w_;
  std::vector<std::string> lines;
  for (const std::string& p : w.written) lines.push_back("snapshot: " + p);
  for (size_t k = w.next_snapshot; k < w.snapshot_times.size(); ++k)
    lines.push_back(fmt::format("snapshot at {} s not written: the run ended at {:.2f} s", w.snapshot_times[k], w.t_last));
  if (w.movie) {
    w.movie->finish();
    lines.push_back(fmt::format("movie: {} ({} frames at {} fps, {} x {} px)", def_.movie_path, w.movie->frames(),
                                def_.movie_fps, w.view->width(), w.view->height()));
    w.movie.reset();
  }
  if (w.vtk) {
    w.vtk->finish();
    lines.push_back(fmt::format("ParaView: {}/run.pvd ({} frames)", def_.vtk_dir, w.vtk->frames()));
  }
  return lines;
}

}  // namespace gapflow
