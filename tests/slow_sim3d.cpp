// Slow tests of the 3D model (label "slow"): the paper's medium discharge and
// the time-step convergence of the flow rate. Numbers measured when written are
// in sim3d/README.md.
#include "sim3d/model3d.hpp"

#include "common/simulation.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace gapflow {
namespace {

TEST(Sim3DSlow, PaperMediumDischargesCompletely) {
  const CompiledScenario sc = testing::compile_file("scenarios/paper/no_obstruction_medium.toml");
  auto session = make_session_3d(sc);
  const RunRecord r = run_simulation(sc, *session);
  std::printf("medium 3D: passed %d of %d in %.2f s, J_paper %.2f /s, wall %.1f s\n", r.passed, r.particles,
              r.sim_time_s, r.j_paper.value_or(-1), r.wall_time_s);
  EXPECT_EQ(r.escaped, 0);
  EXPECT_EQ(r.max_conservation_error, 0);
  EXPECT_EQ(r.passed, r.particles);
  EXPECT_EQ(r.end_reason, EndReason::all_passed);
}

struct MeanJ {
  double mean = 0;       // particles/s
  double half_ci95 = 0;  // particles/s
  int incomplete = 0;    // runs that did not discharge completely
};

// Mean of J between the 10 % and 90 % crossings over replicates (no shaking; W = 5 d
// so that clogs are rare and J measures the flow itself).
MeanJ mean_j(double time_step_s, int replicates) {
  const std::string toml =
      "[scenario]\nname = \"sim3d convergence\"\n"
      "[plane]\nlength_mm = 300.0\nwidth_mm = 120.0\n"
      "[bottleneck]\ngap_mm = 39.0\n"
      "[particles]\ncount = 150\n"
      "[release]\nsettle_s = 0.2\n"
      "[run]\ntime_limit_s = 20.0\nstop_after_no_flow_s = 3.0\n";
  std::vector<double> j;
  MeanJ m;
  for (int rep = 0; rep < replicates; ++rep) {
    const CompiledScenario sc = testing::compile_text(
        toml, {"model.bullet.time_step_s=" + std::to_string(time_step_s), "run.replicate=" + std::to_string(rep)});
    auto session = make_session_3d(sc);
    const RunRecord r = run_simulation(sc, *session);
    EXPECT_EQ(r.escaped, 0);
    if (r.passed != r.particles) ++m.incomplete;
    if (r.j_mid) j.push_back(*r.j_mid);
  }
  const double n = static_cast<double>(j.size());
  for (double v : j) m.mean += v / n;
  double var = 0;
  for (double v : j) var += (v - m.mean) * (v - m.mean) / (n - 1);
  m.half_ci95 = 1.96 * std::sqrt(var / n);
  return m;
}

TEST(Sim3DSlow, FlowRateConvergesInTimeStep) {
  const double dt = BulletDef{}.time_step_s;  // the default step
  const int replicates = 40;
  const MeanJ coarse = mean_j(dt, replicates);
  const MeanJ fine = mean_j(dt / 4, replicates);
  std::printf("J_mid at dt = %g s: %.3f +- %.3f /s; at dt/4: %.3f +- %.3f /s (95 %%); incomplete %d, %d\n", dt,
              coarse.mean, coarse.half_ci95, fine.mean, fine.half_ci95, coarse.incomplete, fine.incomplete);
  // The comparison only means something if the intervals are tighter than the tolerance.
  ASSERT_LT(coarse.half_ci95, 0.02 * fine.mean) << "add replicates";
  ASSERT_LT(fine.half_ci95, 0.02 * fine.mean) << "add replicates";
  EXPECT_NEAR(coarse.mean, fine.mean, 0.02 * fine.mean);
}

}  // namespace
}  // namespace gapflow
