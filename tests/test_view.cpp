// Seeing a run (view/): top-view pixels of hand-placed spheres in both models,
// the ParaView series read back by VTK's own reader, movies checked by ffprobe,
// and the run outputs wired through the StepObserver.
#include "view/movie.hpp"
#include "view/run_outputs.hpp"
#include "view/top_view.hpp"
#include "view/vtk_series.hpp"

#include "sim2d/session2d.hpp"
#include "sim3d/session3d.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <memory>
#include <string>

namespace gapflow {
namespace {

using testing::compile_file;
using testing::TempDir;

// A few grey levels of slack for anti-aliasing and the float engines.
void expect_colour(Rgb got, Rgb want, const std::string& where) {
  EXPECT_NEAR(got.r, want.r, 3) << where;
  EXPECT_NEAR(got.g, want.g, 3) << where;
  EXPECT_NEAR(got.b, want.b, 3) << where;
}

// Hand placement: sphere 0 at rest at A, sphere 1 moving at 0.25 m/s at B, every other retired.
constexpr Vec2 kA{0.0, 0.10}, kB{0.05, 0.30};
constexpr double kSpeedB = 0.25;

void retire_all_but_two(EngineSession& s, const CompiledScenario& sc) {
  std::vector<int> others;
  for (int i = 2; i < static_cast<int>(sc.particles.size()); ++i) others.push_back(i);
  s.retire(others);
}

FrameState capture(const CompiledScenario& sc, const EngineSession& s) {
  GapMonitor monitor(sc);
  std::vector<ParticleMotion> scratch;
  return capture_frame(sc, s, monitor, 1.0, 0, scratch);
}

void check_picture(const CompiledScenario& sc, const FrameState& f) {
  ASSERT_EQ(f.particles.size(), 2u);
  TopView view(sc, TopViewDef{});
  view.draw(f);
  expect_colour(view.colour_at(view.to_pixel(kA)), speed_colour(0, 0.5), "sphere at rest");
  expect_colour(view.colour_at(view.to_pixel(kB)), speed_colour(kSpeedB, 0.5), "sphere at 0.25 m/s");
  expect_colour(view.colour_at(view.to_pixel({-sc.channel_width / 2 - sc.wall_thickness / 2, 0.5})), wall_colour(),
                "left retaining wall");
  // Inside the right bottleneck wall: half a thickness behind the middle of its inner face.
  const Vec2 top{sc.channel_width / 2, sc.funnel_height};
  const Vec2 in_wall{(sc.right_tip.x + top.x) / 2 - sc.right_wall_normal.x * sc.wall_thickness / 2,
                     (sc.right_tip.y + top.y) / 2 - sc.right_wall_normal.y * sc.wall_thickness / 2};
  expect_colour(view.colour_at(view.to_pixel(in_wall)), wall_colour(), "right bottleneck wall");
  expect_colour(view.colour_at(view.to_pixel({-0.05, 0.6})), board_colour(), "empty board");
  expect_colour(view.colour_at(view.to_pixel(sc.obstruction.circle.centre)), obstruction_colour(), "cylinder");
  // The two colours differ, so the check can fail.
  const Rgb a = speed_colour(0, 0.5), b = speed_colour(kSpeedB, 0.5);
  EXPECT_GT(std::abs(a.g - b.g), 100);
}

TEST(TopView, HandPlacedSpheres2D) {
  const CompiledScenario sc = compile_file("scenarios/paper/cylinder.toml", {"obstruction.distance_mm=200"});
  Session2D s(sc);
  retire_all_but_two(s, sc);
  s.reinject({{0, kA}, {1, kB}});
  World2D& w = s.world();
  w.particles[1]->SetLinearVelocity({0.0f, static_cast<float>(-w.scale.to_engine_velocity(kSpeedB))});
  const FrameState f = capture(sc, s);
  EXPECT_NEAR(f.particles[0].z, sc.particles[0].diameter / 2, 1e-12);
  check_picture(sc, f);
}

TEST(TopView, HandPlacedSpheres3D) {
  const CompiledScenario sc = compile_file("scenarios/paper/cylinder.toml", {"obstruction.distance_mm=200"});
  Session3D s(sc);
  retire_all_but_two(s, sc);
  s.place(0, {kA.x, kA.y, s.radius(0)});
  s.place(1, {kB.x, kB.y, s.radius(1)}, {0, -kSpeedB, 0});
  const FrameState f = capture(sc, s);
  EXPECT_NEAR(f.particles[1].z, s.radius(1), 1e-9);
  check_picture(sc, f);
}

TEST(TopView, StateColoursMarkTheClogFront) {
  const CompiledScenario sc = compile_file("scenarios/paper/no_obstruction_medium.toml");
  FrameState f;
  f.model = "2d";
  const double r = sc.nominal_diameter / 2;
  // Two spheres side by side above the gap (the front), one right behind them (hidden).
  f.particles = {{0, -r, r}, {1, r, r}, {2, 0, 3 * r}};
  for (ParticleView& p : f.particles) p.radius = r;
  mark_clog_front(sc, f);
  EXPECT_EQ(f.particles[0].state, ParticleState::arch);
  EXPECT_EQ(f.particles[1].state, ParticleState::arch);
  EXPECT_EQ(f.particles[2].state, ParticleState::stuck);
  TopViewDef def;
  def.colour_by = Colouring::state;
  def.px_per_mm = 4;
  TopView view(sc, def);
  view.draw(f);
  expect_colour(view.colour_at(view.to_pixel({-r, r})), state_colour(ParticleState::arch), "arch sphere");
  expect_colour(view.colour_at(view.to_pixel({0, 3 * r})), state_colour(ParticleState::stuck), "sphere behind");
}

// Debian's python3-vtk9 lives in the system interpreter; a pyenv python3 earlier on PATH lacks it.
std::string python_with_vtk() {
  for (const char* py : {"/usr/bin/python3", "python3"})
    if (std::system(fmt::format("{} -c 'import vtkmodules.vtkIOXML' >/dev/null 2>&1", py).c_str()) == 0) return py;
  return "";
}

TEST(VtkSeries, ReadBackByVtk) {
  const std::string python = python_with_vtk();
  if (python.empty()) GTEST_SKIP() << "python3-vtk9 is not installed (scripts/setup.sh installs it)";
  const CompiledScenario sc = compile_file("scenarios/paper/cylinder.toml", {"obstruction.distance_mm=200"});
  TempDir dir("vtk");
  VtkSeries series(sc, dir.path().string());
  for (int k = 0; k < 2; ++k) {
    FrameState f;
    f.model = "3d";
    f.t = 0.5 * k;
    f.offsets.obstruction = {0.001 * k, 0};
    ParticleView p;
    p.id = 7, p.x = 0.01, p.y = 0.2, p.z = 0.004, p.radius = 0.0039, p.vx = 0.1, p.vy = -0.2, p.vz = 0.01;
    p.wx = 1, p.wy = 2, p.wz = 3, p.state = ParticleState::arch;
    f.particles = {p, p, p};
    f.particles[2].id = 9, f.particles[2].state = ParticleState::passed;
    series.write(f);
  }
  series.finish();
  const std::string cmd = fmt::format("{} {} {}", python, testing::source_path("tests/vtk_roundtrip.py").string(),
                                      dir.path().string());
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
}

bool has_ffmpeg() { return !find_on_path("ffmpeg").empty() && !find_on_path("ffprobe").empty(); }

std::string ffprobe(const std::filesystem::path& movie) {
  const std::string cmd = fmt::format(
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames,width,height "
      "-of csv=p=0 '{}'", movie.string());
  std::string out;
  FILE* p = ::popen(cmd.c_str(), "r");
  char buf[256];
  while (p && std::fgets(buf, sizeof buf, p)) out += buf;
  if (p) ::pclose(p);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out;
}

// A short 2D run with every output on: the snapshots, the movie's frame count and
// size (ffprobe) and the ParaView frames follow the schedule.
TEST(RunOutputs, ShortRunWritesEveryOutput) {
  if (!has_ffmpeg()) GTEST_SKIP() << "ffmpeg/ffprobe not installed (scripts/setup.sh installs ffmpeg)";
  const CompiledScenario sc = compile_file("scenarios/paper/no_obstruction_medium.toml",
                                           {"particles.count=150", "release.settle_s=0.1", "run.end=\"time_limit\"",
                                            "run.time_limit_s=1.0"});
  TempDir dir("outputs");
  RunOutputDef def;
  def.snapshot_times_s = {0.5, 0.0, 5.0};
  def.snapshot_dir = (dir / "snaps").string();
  def.movie_path = (dir / "run.mp4").string();
  def.movie_fps = 10;
  def.vtk_dir = (dir / "vtk").string();
  def.vtk_interval_s = 0.25;
  RunOutputs outputs(sc, def);
  run_model(sc, ModelKind::box2d, &outputs.observer());
  const std::vector<std::string> lines = outputs.finish();
  EXPECT_TRUE(std::filesystem::exists(dir / "snaps/t0000.00s.png"));
  EXPECT_TRUE(std::filesystem::exists(dir / "snaps/t0000.50s.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "snaps/t0005.00s.png"));
  EXPECT_NE(std::find(lines.begin(), lines.end(), "snapshot at 5 s not written: the run ended at 1.00 s"), lines.end());
  TopView view(sc, TopViewDef{});
  // Frames at 0, 0.1, ..., 1.0 s of the 1 s run.
  EXPECT_EQ(ffprobe(dir / "run.mp4"), fmt::format("{},{},11", view.width(), view.height()));
  EXPECT_FALSE(std::filesystem::exists(dir / "run.mp4.partial"));
  EXPECT_TRUE(std::filesystem::exists(dir / "vtk/particles_000004.vtp"));
  EXPECT_FALSE(std::filesystem::exists(dir / "vtk/particles_000005.vtp"));
  EXPECT_TRUE(std::filesystem::exists(dir / "vtk/run.pvd"));
}

TEST(RunOutputs, MissingFfmpegIsBadInput) {
  const char* old = std::getenv("PATH");
  const std::string saved = old ? old : "";
  ::setenv("PATH", "/nonexistent", 1);
  RunOutputDef def;
  def.movie_path = "never.mp4";
  try {
    def.validate();
    ADD_FAILURE() << "no error without ffmpeg";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("apt-get install ffmpeg"), std::string::npos) << e.what();
  }
  ::setenv("PATH", saved.c_str(), 1);
  EXPECT_FALSE(std::filesystem::exists("never.mp4"));
}

}  // namespace
}  // namespace gapflow
