// The calibration loop end to end on a model with a closed form instead of the simulator: every
// run of the design is a formula with known responses to the free parameter and to the effects,
// so what the loop decides (which candidates it fits in full, which it tries, where it measures an
// effect's response again, the size it reports) can be checked against the truth exactly and in
// seconds. The simulator's own end-to-end checks are in test_calibration.cpp.
#include "calibrate/calibration.hpp"
#include "calibrate/data_file.hpp"
#include "calibrate/effect_responses.hpp"
#include "calibrate/fit.hpp"
#include "calibrate/evaluator.hpp"
#include "calibrate/twin.hpp"
#include "common/random.hpp"
#include "common/statistics.hpp"
#include "studies/jobs.hpp"
#include "studies/runner.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace gapflow {
namespace {

using testing::source_path;
using testing::TempDir;

// ln J_mid (J in particles/s) of a run, by formula. The flow rises with the gap (as W^1.5) and the
// incline and falls with the particle friction mu; three effects act with shapes that differ over
// the design: linear drag gamma (1/s) more on the steep board (fast flow), and its size per unit
// scales with 1 + kDragFrictionCoupling (mu - 0.3) (an effect's response depends on the free
// parameter, as in the simulator: the reason the loop measures it again near the fit); spinning
// friction s (mm) like drag but stronger at narrow gaps (a rival that correlates with drag, not a
// twin of it); rolling resistance mu_r more on the shallow board. Every other catalogue effect
// moves nothing. A drag outside the catalogue, quadratic in the speed (particles.quadratic_drag_per_m,
// c in 1/m), slows the flow as -0.06 c steep^2.5: per unit of a linear drag's effect it grows with the
// board's steepness, as a force c v^2 = (c v) v does with the speed (form_check.hpp's case). The
// exponent is a stand-in chosen to part from the linear form with the incline, not derived from the
// simulator's mechanics.
// Noise: a part common to every parameter value of the same seed, replicate and
// point (common random numbers) and a part of its own at every parameter value (as a simulator's
// chaotic dynamics give), so paired differences have noise too.
constexpr double kDragFrictionCoupling = 2.5;
// A lateral tilt phi (deg) slows the flow as -g_tilt_curvature phi^2 (W/d / 4.5) / steep: even in
// phi (the board mirrored is the same board), more on shallow boards (the cross-slope pull against
// the downslope one) and at wide gaps (a shape no other effect here has). 0 (the tilt moves
// nothing) except where a test sets it (TiltScope).
double g_tilt_curvature = 0;
// A part of spinning friction's response that is the same at every point (ln J per mm): as the
// simulator's, which on J_mid acts much as the particle friction raised (0.86 mm as +0.130 in the
// friction at W/d 4.5; results/spinning-friction-interaction/). 0 except where a test sets it
// (SpinLevelScope): the closed form's spinning friction is otherwise shaped like drag.
double g_spin_level = 0;
// How that level part changes with the particle friction mu: times 1 + g_spin_coupling (mu - 0.3)
// (an effect whose response depends on the free parameter; 0 except where a test sets it).
double g_spin_coupling = 0;
struct NoiseLevels {
  double common = 0.03, own = 0.01;  // standard deviations on ln J
  // Which runs carry the own part: all, only those with a drag (the twin's data and drag's
  // responses), or only those without (the surface's nodes and every response's reference runs).
  enum class OwnIn { all, drag_runs, drag_free_runs } own_in = OwnIn::all;
};
NoiseLevels g_noise;  // a test may change it (NoiseScope)

// Sets one of the closed-form model's settings (g_noise, g_tilt_curvature, g_spin_level,
// g_spin_coupling) for one test and restores it after.
template <class T>
class SettingScope {
 public:
  SettingScope(T& setting, T value) : setting_(setting), saved_(setting) { setting_ = value; }
  ~SettingScope() { setting_ = saved_; }
  SettingScope(const SettingScope&) = delete;
  SettingScope& operator=(const SettingScope&) = delete;

 private:
  T& setting_;
  T saved_;
};
struct NoiseScope : SettingScope<NoiseLevels> {
  explicit NoiseScope(NoiseLevels levels) : SettingScope(g_noise, levels) {}
};
struct TiltScope : SettingScope<double> {
  explicit TiltScope(double curvature) : SettingScope(g_tilt_curvature, curvature) {}
};
struct SpinLevelScope : SettingScope<double> {
  explicit SpinLevelScope(double level) : SettingScope(g_spin_level, level) {}
};
struct SpinCouplingScope : SettingScope<double> {
  explicit SpinCouplingScope(double coupling) : SettingScope(g_spin_coupling, coupling) {}
};

double own_noise_scale(const ScenarioDef& d) {
  if (g_noise.own_in == NoiseLevels::OwnIn::all) return 1;
  return (g_noise.own_in == NoiseLevels::OwnIn::drag_runs) == (d.particles.drag_per_s != 0) ? 1 : 0;
}

double synthetic_ln_j(const CompiledScenario& sc, double common_noise, double own_noise) {
  const ScenarioDef& d = sc.def;
  const double w_over_d = (d.bottleneck.gap_mm + d.bottleneck.gap_offset_mm) / d.particles.diameter_mm;
  const double steep = std::sin(d.plane.incline_deg * M_PI / 180) / std::sin(8 * M_PI / 180);
  const double mu = d.particles.friction_particle;
  return std::log(50.0) + 1.5 * std::log(w_over_d / 4.5) + 0.7 * std::log(steep) - 2.0 * (mu - 0.3) -
         0.06 * d.particles.drag_per_s * steep * (1 + kDragFrictionCoupling * (mu - 0.3)) -
         0.06 * d.particles.quadratic_drag_per_m * std::pow(steep, 2.5) -
         0.04 * d.particles.spinning_friction_mm * steep * 4.5 / w_over_d -
         g_spin_level * (1 + g_spin_coupling * (mu - 0.3)) * d.particles.spinning_friction_mm -
         6.0 * d.particles.rolling_resistance / steep -
         g_tilt_curvature * std::pow(d.plane.lateral_tilt_deg, 2) * (w_over_d / 4.5) / steep +
         g_noise.common * common_noise + own_noise_scale(d) * g_noise.own * own_noise;
}

RunRecord synthetic_run(const Job& job, const std::atomic<bool>*) {
  const CompiledScenario sc = compile_job(job);
  // The common part is drawn from what a parameter value does not change: seed, replicate, point.
  const std::uint64_t point = mix_seed(static_cast<std::uint64_t>(std::llround(sc.def.bottleneck.gap_mm * 1000)),
                                       static_cast<std::uint64_t>(std::llround(sc.def.plane.incline_deg * 1000)));
  RandomStream common(mix_seed(mix_seed(sc.def.run.seed, static_cast<std::uint64_t>(sc.def.run.replicate)), point));
  RandomStream own(sc.run_seed);  // mixes the scenario's hash: new at every parameter value
  RunRecord r;
  r.model = to_string(job.model);
  r.scenario_name = sc.def.name;
  r.scenario_hash = sc.scenario_hash;
  r.base_seed = sc.def.run.seed;
  r.replicate = sc.def.run.replicate;
  r.run_seed = sc.run_seed;
  r.diameter_m = sc.nominal_diameter;
  r.gap_m = sc.declared_gap;
  r.incline_rad = sc.incline;
  r.particles = 150;
  r.passed = 150;
  r.j_mid = std::exp(synthetic_ln_j(sc, common.normal(), own.normal()));
  r.sim_time_s = 150 / *r.j_mid;
  r.wall_time_s = 1e-3;
  return r;
}

// Every job of a calibration or a twin through the formula (an EvaluatorOptions::runner).
RunnerSummary run_synthetic(const std::vector<Job>& jobs, Store& store, const RunnerOptions& options) {
  RunnerOptions o = options;
  o.run = synthetic_run;
  return run_jobs(jobs, store, o);
}

// Nine fitted points (W/d 3.5, 4.5, 5.5 x incline 5, 8, 12 deg) and two held out, J_mid on a log
// scale, the particle friction free on 0.1-0.5 (grid step 0.05); `model_replicates` model runs per point
// from base seed `model_seed`; with `shallow_held_out`, a third held-out point on a shallower board
// (3 deg) than any fitted one, where the design extrapolates; with `more_gaps`, the gaps W/d 3.5-5.5
// in steps of 0.5 (15 fitted points), so that more of the residual is left beside any one test.
// With `friction_measured_se` > 0 the friction carries an independent measurement of that standard
// error (as the blind designs'; the twin writes its reading).
void write_design(const std::filesystem::path& file, int model_replicates, std::uint64_t model_seed,
                  bool shallow_held_out = false, bool more_gaps = false, double friction_measured_se = 0) {
  std::ofstream f(file);
  f << "[data]\nname = \"synthetic\"\n"
    << "[source]\ncitation = \"a closed-form model (tests/test_calibration_synthetic.cpp)\"\n"
    << "method = \"simulated\"\nuncertainty = \"placeholders\"\n"
    << "[model]\nscenario = \"" << source_path("scenarios/paper/no_obstruction_medium.toml").string() << "\"\n"
    << "replicates = " << model_replicates << "\nseed = " << model_seed << "\n"
    << "[observable]\nkind = \"j_mid\"\nfloor_relative = 0.005\n"
    << "[[design]]\ncolumn = \"W_over_d\"\nkey = \"bottleneck.gap_mm\"\nunit = \"d\"\n"
    << "[[design]]\ncolumn = \"incline_deg\"\nkey = \"plane.incline_deg\"\n"
    << "[[free]]\nkey = \"particles.friction_particle\"\nlo = 0.1\nhi = 0.5\nstep = 0.05\n";
  if (friction_measured_se > 0) f << "measured = 0.3\nmeasured_se = " << friction_measured_se << "\n";
  const std::vector<double> gaps = more_gaps ? std::vector<double>{3.5, 4.0, 4.5, 5.0, 5.5} : std::vector<double>{3.5, 4.5, 5.5};
  for (double w : gaps)
    for (double incline : {5.0, 8.0, 12.0})
      f << "[[point]]\nW_over_d = " << w << "\nincline_deg = " << incline << "\nvalue = 1\nuncertainty = 1\n";
  f << "[[point]]\nW_over_d = 4\nincline_deg = 10\nvalue = 1\nuncertainty = 1\nheld_out = true\n";
  f << "[[point]]\nW_over_d = 5\nincline_deg = 6\nvalue = 1\nuncertainty = 1\nheld_out = true\n";
  if (shallow_held_out) f << "[[point]]\nW_over_d = 4.5\nincline_deg = 3\nvalue = 1\nuncertainty = 1\nheld_out = true\n";
}

struct SyntheticRun {
  CalibrationResult result;
  std::string log;  // every decision of the loop (CalibrationResult::log), one a line
};

// What a synthetic twin varies besides its effects: the true friction, the twin's seed (its data's
// noise), and the calibration's model runs per point and base seed (the model's noise).
struct SyntheticCase {
  double friction = 0.3;
  std::uint64_t twin_seed = 3;
  int model_replicates = 4;
  std::uint64_t model_seed = 1;
  bool shallow_held_out = false;  // write_design's
  bool more_gaps = false;         // write_design's
  bool held_out_route = false;    // CalibrationDef's
  int alternatives = 0;           // CalibrationDef's (not its default: the other rules tested alone and cheaply;
                                  // rule 5 changes nothing they check but the verdict's wording, tested on its own)
  bool independent_signatures = CalibrationDef{}.independent_signatures;
  std::vector<std::string> outside = {};  // key=value planted outside the catalogue (the twin's --set)
};

// The twin (10 runs per point) of the design written in `dir`, made through the formula with `twin`'s
// seed, effects and overrides; its data file is dir/twin.toml.
TwinTruth make_synthetic_twin(const TempDir& dir, TwinDef twin) {
  const DataFile design = load_data_file(dir / "design.toml");
  EvaluatorOptions eo;
  eo.runner = run_synthetic;
  Store twin_store(dir / "twin.sqlite");
  Evaluator twin_ev(design, twin_store, eo);
  twin.name = "synthetic-twin";
  twin.replicates = 10;
  return make_twin(design, twin, twin_ev, dir / "twin.toml", dir / "truth.json");
}

// The calibration of dir/twin.toml through the formula.
CalibrationResult calibrate_synthetic_twin(const TempDir& dir, const CalibrationDef& def) {
  const DataFile data = load_data_file(dir / "twin.toml");
  EvaluatorOptions eo;
  eo.runner = run_synthetic;
  Store store(dir / "cal.sqlite");
  Evaluator ev(data, store, eo);
  return calibrate(data, def, ev);
}

// A twin of the design with `effects` planted (and the case's friction and seeds), calibrated blind.
SyntheticRun calibrate_synthetic(const TempDir& dir, const std::vector<std::string>& effects, int contenders,
                                 const SyntheticCase& c = {}) {
  write_design(dir / "design.toml", c.model_replicates, c.model_seed, c.shallow_held_out, c.more_gaps);
  TwinDef twin;
  twin.seed = c.twin_seed;
  twin.effects = effects;
  twin.set = {"particles.friction_particle=" + std::to_string(c.friction)};
  for (const std::string& kv : c.outside) twin.set.push_back(kv);
  (void)make_synthetic_twin(dir, twin);
  CalibrationDef def;
  def.contenders = contenders;
  def.held_out_route = c.held_out_route;
  def.alternatives = c.alternatives;
  def.independent_signatures = c.independent_signatures;
  SyntheticRun run{calibrate_synthetic_twin(dir, def), ""};
  for (const std::string& line : run.result.log) run.log += line + "\n";
  return run;
}

double friction(const ModelState& s) { return s.params.get("particles.friction_particle", -1); }

// The explorations' knobs: an environment variable, or the fallback where it is unset.
double knob(const char* name, double fallback) {
  const char* v = std::getenv(name);
  return v ? std::stod(v) : fallback;
}
std::string text_knob(const char* name, const char* fallback) {
  const char* v = std::getenv(name);
  return std::string(v ? v : fallback);
}

// A candidate's score as z = estimate / se, signed so that positive points toward its step.
double z_toward_step(const Candidate& k) {
  const double z = k.score.estimate * k.score.projected_norm;  // se = 1 / |u~|
  return k.step > 0 ? z : -z;
}

// Drag alone was added, its 95 % interval holds the planted size, and the friction is back near its truth.
void expect_drag_found(const SyntheticRun& run, double planted, double true_friction) {
  const CalibrationResult& r = run.result;
  ASSERT_EQ(r.effects.size(), 1u) << r.verdict << "\n" << run.log;
  const AddedEffect& drag = r.effects.front();
  EXPECT_EQ(drag.effect, "linear_drag");
  EXPECT_LE(drag.lo95, planted);
  EXPECT_GE(drag.hi95, planted) << drag.value;
  EXPECT_NEAR(friction(r.after), true_friction, 0.025);
}

// Drag planted at 4 /s: the baseline fit, without drag, takes up its mean by raising the friction
// (to ~0.42, far from 0.3), where drag's response is 1.3 x its response at the true friction. The
// loop must find drag, measure its response again at the nodes nearest the joint fit, and report a
// size whose interval holds 4; measured only at the baseline's node the size would be ~3.
TEST(CalibrationSynthetic, ADragFoundAtAFrictionFarFromTheBaselinesIsMeasuredAgainThereAndSizedRight) {
  TempDir dir("gapflow_calibration_synthetic");
  const SyntheticRun run = calibrate_synthetic(dir, {"linear_drag=4"}, 3);
  const CalibrationResult& r = run.result;
  EXPECT_GT(friction(r.before), 0.375) << "the premise: the baseline's friction two nodes or more from the truth";
  expect_drag_found(run, 4.0, 0.3);
  EXPECT_NE(run.log.find("linear_drag: the fit moved the free parameters"), std::string::npos) << run.log;
  // Its sizes measured in one batch against the same runs: their correlation is counted (J only:
  // one group; the model's runs part within a few collisions, so near 1/2, EffectTerm::response).
  ASSERT_EQ(r.effects.size(), 1u);
  EXPECT_GE(r.effects[0].size_correlation, 0.0);
  EXPECT_LE(r.effects[0].size_correlation, 1.0);
  EXPECT_NE(run.log.find("linear_drag: its sizes' errors correlate between neighbouring sizes, counted"),
            std::string::npos)
      << run.log;
  // The drag planted is the catalogue's: one size fits every incline and gap, and the form check
  // (form_check.hpp) says so.
  ASSERT_FALSE(r.form_checks.empty());
  EXPECT_FALSE(r.form_differs) << r.verdict;
  // Its law in the speed, though, this design (5-12 deg, 4 model replicates) cannot determine: the
  // check along the incline would hardly see a quadratic drag read as linear (form_check.hpp).
  EXPECT_LT(r.law_power, 0.8);
  EXPECT_TRUE(r.law_undetermined);
  EXPECT_EQ(r.verdict,
            "effect found; the drag's law in the speed is not established: a drag of another law may be acting");
}

// A drag of another form than the catalogue's (quadratic in the speed: here 1.5 steep^2.5 against
// the linear drag's steep) is read as a linear drag, the nearest catalogue effect; the one size it
// is given fits no incline, and the form check (form_check.hpp) flags it along the incline, not
// along the gap, which the drag of either form does not depend on. On the 15-point design at 16
// model replicates (on the 9-point one too little residual is left beside the test for its F).
// Over twins 3-10 (DISABLED_FormCheckRates below, a456b2f): this drag flagged in 8 of 8 at 16 model
// replicates and 6 of 8 at 4; a linear drag of 4 /s, the catalogue's own form, in 1 of 8
// (results/calibration-blind-pass20/replay-formcheck/closed_form_rates.txt).
TEST(CalibrationSynthetic, ADragOfAnotherFormReadAsLinearDragIsFlaggedByTheFormCheck) {
  TempDir dir("gapflow_calibration_synthetic");
  SyntheticCase c;
  c.outside = {"particles.quadratic_drag_per_m=1.5"};
  c.model_replicates = 16;
  c.more_gaps = true;
  const SyntheticRun run = calibrate_synthetic(dir, {}, 1, c);
  const CalibrationResult& r = run.result;
  ASSERT_EQ(r.effects.size(), 1u) << "the premise: one effect is added\n" << r.verdict << "\n" << run.log;
  EXPECT_EQ(r.effects.front().effect, "linear_drag");
  EXPECT_TRUE(r.form_differs);
  // The flag is reported, not in the verdict (decisions.hpp, rule 3). The verdict is the law's
  // reservation: the surface's chi^2 at the fit is 23.9 on 13 (p = 0.033), not poor enough for "poor
  // fit remains" (40.6 on fresh seeds). It has moved with the surface's variance: 24.4 (p = 0.027)
  // and this verdict until the surface counted the noise its first effect shares with its quadratic
  // (fit.hpp, Surface::predict); 28.2 (p = 0.008), "effect found, poor fit remains", until it counted
  // the noise its nodes share (calibrate/node_correlation.hpp: this model's replicates correlate
  // about +0.9 between neighbouring nodes).
  EXPECT_EQ(r.verdict, "effect found; the drag's law in the speed is not established: a drag of another law may be acting");
  EXPECT_TRUE(r.law_undetermined);
  for (const FormCheck& k : r.form_checks) {
    if (k.column == "incline_deg") {
      EXPECT_LT(k.p_adjusted, 0.05) << k.statistic << " / " << k.scale << " on " << k.dof;
    }
    if (k.column == "W_over_d") {
      EXPECT_GT(k.p_adjusted, 0.05) << k.statistic << " / " << k.scale << " on " << k.dof;
    }
  }
  EXPECT_EQ(r.form_checks.size(), 2u);
}

// The same design and replicates with a drag of the catalogue's own form: found, and not flagged
// (on a correct attribution the check flags at a rate of at most 5 % a calibration).
TEST(CalibrationSynthetic, ALinearDragOnTheSameDesignIsNotFlaggedByTheFormCheck) {
  TempDir dir("gapflow_calibration_synthetic");
  SyntheticCase c;
  c.model_replicates = 16;
  c.more_gaps = true;
  const SyntheticRun run = calibrate_synthetic(dir, {"linear_drag=4"}, 1, c);
  const CalibrationResult& r = run.result;
  ASSERT_EQ(r.effects.size(), 1u) << r.verdict << "\n" << run.log;
  EXPECT_EQ(r.effects.front().effect, "linear_drag");
  ASSERT_FALSE(r.form_checks.empty());
  EXPECT_FALSE(r.form_differs) << r.verdict;
  // This closed form's outside drag (above) parts from the linear one as steep^1.5, and the check
  // flags it; a drag quadratic in the speed parts only as sqrt(sin theta), and against that the
  // check along 5-12 deg has little power even at 16 replicates (0.27 when written): the linear
  // drag is found, its law is not determined, and the verdict says so.
  EXPECT_GT(r.law_power, 0.05);
  EXPECT_LT(r.law_power, 0.8);
  EXPECT_EQ(r.verdict,
            "effect found; the drag's law in the speed is not established: a drag of another law may be acting");
}

// The truth beyond the baseline's surface: drag at 5 /s with the friction at 0.2 puts the
// baseline's friction at 0.33 (nearest node 0.35: its surface through the nodes 0.25-0.45; the
// margin to 0.325 is small, but the run is deterministic). Bounded by that surface the joint fit
// stopped at 0.25 with the drag at 2.5 (c1dbc0d); moved twice, to the surface around where it
// stopped, it reaches the truth.
TEST(CalibrationSynthetic, AFitThatEndsAtItsSurfacesBoundIsFittedAgainOnTheSurfaceAroundIt) {
  TempDir dir("gapflow_calibration_synthetic_beyond");
  const SyntheticRun run = calibrate_synthetic(dir, {"linear_drag=5"}, 3, {.friction = 0.2});
  const CalibrationResult& r = run.result;
  EXPECT_GT(friction(r.before), 0.325) << "the premise: the truth more than a node beyond the baseline's surface";
  expect_drag_found(run, 5.0, 0.2);
  std::size_t refits = 0;
  for (const std::string& line : r.log) refits += line.rfind("linear_drag: re-fitted on the response", 0) == 0;
  EXPECT_GE(refits, 2u) << "the surface moved once at most: the fit never left the baseline's surface\n" << run.log;
  // Each state records the window of the surface it was read from (summary.json surface_window), and
  // its friction lies inside it: the baseline's window above the truth 0.2, the final one moved down
  // with the fit to hold it.
  for (const ModelState* s : {&r.before, &r.after}) {
    ASSERT_EQ(s->window_keys, std::vector<std::string>{"particles.friction_particle"});
    EXPECT_LE(s->window_lo[0], friction(*s));
    EXPECT_GE(s->window_hi[0], friction(*s));
  }
  EXPECT_GT(r.before.window_lo[0], 0.2);
  EXPECT_LE(r.after.window_lo[0], 0.2);
  EXPECT_GE(r.after.window_hi[0], 0.2);
}

// Spinning friction's signature correlates with drag's: both are significant, each is fitted in
// full, and the planted one has the lower BIC and is the one tried, whichever scores best.
TEST(CalibrationSynthetic, WhenTwoCandidatesAreSignificantBothAreFittedAndThePlantedOneIsTried) {
  TempDir dir("gapflow_calibration_synthetic_contest");
  const SyntheticRun run = calibrate_synthetic(dir, {"linear_drag=4"}, 3);
  ASSERT_FALSE(run.result.rounds.empty());
  const Round& first = run.result.rounds.front();
  ASSERT_GE(first.fits.size(), 2u) << run.log;
  const auto fit_of = [&](const std::string& effect) {
    return std::find_if(first.fits.begin(), first.fits.end(), [&](const ContenderFit& f) { return f.effect == effect; });
  };
  ASSERT_NE(fit_of("linear_drag"), first.fits.end());
  ASSERT_NE(fit_of("spinning_friction"), first.fits.end()) << run.log;
  EXPECT_LT(fit_of("linear_drag")->bic, fit_of("spinning_friction")->bic);
  EXPECT_EQ(first.best, "linear_drag");
  // What it cost this process (every thread), apart from the runs' summed wall times.
  EXPECT_GT(run.result.cpu_seconds, 0);

  // With one contender the best score is tried and nothing is fitted beforehand.
  TempDir one("gapflow_calibration_synthetic_one");
  const SyntheticRun single = calibrate_synthetic(one, {"linear_drag=4"}, 1);
  ASSERT_FALSE(single.result.rounds.empty());
  EXPECT_TRUE(single.result.rounds.front().fits.empty());
}

// Rule 5 (decisions.hpp): with alternatives asked for, the other significant candidates are fitted
// beside the one tried, and one that alone leaves the fitted points within the noise is named and
// withholds the verdict's identity; the effect tried, its size and the keep test are those of the
// loop without them. Spinning friction here acts like drag scaled by 4.5 / (W/d): on these gaps
// (3.5-5.5 d) a large drag tells them apart, a small one leaves either within the noise. On twin seed
// 6: since the surface counts the noise its nodes share (calibrate/node_correlation.hpp), the small
// drag's premise (one effect added, spinning friction within the noise) held on twin seeds 2 and 6 of
// 1-7; on seed 3, this test's until then, spinning friction now scores first and the keep test
// rejects it, and nothing is added.
TEST(CalibrationSynthetic, AlternativesThatAloneFitWithinTheNoiseAreNamedAndChangeNothingElse) {
  const double small = knob("GAPFLOW_ALT_SMALL", 1.0), large = knob("GAPFLOW_ALT_LARGE", 4.0);
  for (double drag : {small, large}) {
    const std::string planted = fmt::format("linear_drag={}", drag);
    TempDir plain_dir("gapflow_calibration_synthetic_alt0"), alt_dir("gapflow_calibration_synthetic_alt1");
    const SyntheticRun plain = calibrate_synthetic(plain_dir, {planted}, 1, {.twin_seed = 6});
    const SyntheticRun alt = calibrate_synthetic(alt_dir, {planted}, 1, {.twin_seed = 6, .alternatives = 1});
    const CalibrationResult &p = plain.result, &a = alt.result;
    ASSERT_EQ(a.effects.size(), 1u) << drag << ": the premise, one effect added\n" << alt.log;
    ASSERT_EQ(p.effects.size(), a.effects.size()) << drag;
    EXPECT_EQ(a.effects[0].effect, p.effects[0].effect) << drag;
    EXPECT_EQ(a.effects[0].value, p.effects[0].value) << drag;
    EXPECT_EQ(a.effects[0].lo95, p.effects[0].lo95) << drag;
    EXPECT_EQ(a.after.fitted.chi.chi2, p.after.fitted.chi.chi2) << drag;
    EXPECT_TRUE(p.rounds.front().fits.empty());
    ASSERT_EQ(a.rounds.size(), p.rounds.size()) << drag;
    for (std::size_t k = 0; k < a.rounds.size(); ++k) {
      EXPECT_EQ(a.rounds[k].decision, p.rounds[k].decision) << drag;  // the keep test's evidence is in it
      EXPECT_EQ(a.rounds[k].best, p.rounds[k].best) << drag;
    }
    const Round& first = a.rounds.front();
    ASSERT_EQ(first.fits.size(), 2u) << drag << "\n" << alt.log;
    EXPECT_EQ(first.fits[0].effect, "linear_drag");
    EXPECT_EQ(first.fits[1].effect, "spinning_friction");
    const bool spinning_within = first.fits[1].fitted.p >= 0.05;
    EXPECT_EQ(first.alternatives, spinning_within ? std::vector<std::string>{"spinning_friction"}
                                                  : std::vector<std::string>{})
        << drag;
    EXPECT_EQ(a.effects[0].alternatives, first.alternatives) << drag;
    if (spinning_within) {
      // The identity withheld, and the drag's law reservation kept where the loop without the rule said it.
      const std::string found = "effect found", law = p.verdict.substr(std::min(found.size(), p.verdict.size()));
      ASSERT_TRUE(p.verdict.starts_with(found)) << drag;
      EXPECT_EQ(a.verdict, found + "; these data do not exclude another effect in its place" + law) << drag;
    } else {
      EXPECT_EQ(a.verdict, p.verdict) << drag;
    }
    std::cout << fmt::format("drag {}: spinning friction's fit chi2 {:.2f} / {} (p {:.3g}); verdict: {}\n", drag,
                             first.fits[1].fitted.chi2, first.fits[1].fitted.dof, first.fits[1].fitted.p, a.verdict);
    // The premise of each size: the small drag leaves spinning friction within the noise, the large does not.
    EXPECT_EQ(spinning_within, drag == small) << drag << "\n" << alt.log;
  }
}

// A lateral tilt slows the flow quadratically (J is even in the tilt), and the loop measures it at
// 0, 2, 4 and 6 deg. A straight line between the sizes reads a planted 4.56 deg as 4.48 (blind
// passes 15-18 fitted every tilt toward neutral, 6 of 8 intervals missing), and with little noise
// its interval misses (4.48 [4.454, 4.509]); interpolated by the shape-preserving cubic the size
// comes within 0.03 deg and the interval holds the truth (4.577 [4.552, 4.601]: the cubic reads a
// quadratic's 4.559 as 4.575).
TEST(CalibrationSynthetic, ACurvedResponseIsSizedWithoutTheStraightLinesBiasTowardNeutral) {
  const NoiseScope quiet({.common = 0.002, .own = 0.0005});  // below the data's floor (0.5 %)
  const TiltScope tilt(0.02);  // ln J per deg^2: -0.42 at 4.56 deg, W/d 4.5, 8 deg
  TempDir dir("gapflow_calibration_synthetic_tilt");
  const SyntheticRun run = calibrate_synthetic(dir, {"lateral_tilt=4.559"}, 1);
  const CalibrationResult& r = run.result;
  ASSERT_EQ(r.effects.size(), 1u) << r.verdict << "\n" << run.log;
  const AddedEffect& found = r.effects.front();
  EXPECT_EQ(found.effect, "lateral_tilt");
  EXPECT_NEAR(found.value, 4.559, 0.03) << run.log;
  EXPECT_LE(found.lo95, 4.559);
  EXPECT_GE(found.hi95, 4.559);
  EXPECT_LT(found.hi95 - found.lo95, 0.16) << "the premise: an interval narrow enough to miss by 0.08 deg";
}

// A twin's data file gives its calibrations the design's model seed unless told another: a blind
// study with a seed per twin calibrates each against its own draw of the model's noise.
TEST(CalibrationSynthetic, ATwinCarriesTheModelSeedItIsGiven) {
  TempDir dir("gapflow_calibration_synthetic_twin_seed");
  write_design(dir / "design.toml", 4, 1);
  const DataFile design = load_data_file(dir / "design.toml");
  EvaluatorOptions eo;
  eo.runner = run_synthetic;
  Store store(dir / "twin.sqlite");
  Evaluator ev(design, store, eo);
  for (const std::optional<std::uint64_t> seed : {std::optional<std::uint64_t>{}, std::optional<std::uint64_t>{15101}}) {
    TwinDef twin;
    twin.name = "seeded";
    twin.seed = 3;
    twin.model_seed = seed;
    const std::string stem = seed ? "with_seed" : "without_seed";
    (void)make_twin(design, twin, ev, dir / (stem + ".toml"), dir / (stem + ".json"));
    EXPECT_EQ(load_data_file(dir / (stem + ".toml")).seed, seed.value_or(design.seed)) << stem;
  }
}

// Rule 1's held-out route (decisions.hpp). A rolling resistance of 0.008 acts as 1/sin(incline):
// over the fitted boards (5-12 deg) the friction takes most of it in and the fitted points stay
// within the noise (chi2 p 0.069 on this twin), but the held-out board at 3 deg, beyond the fitted
// ones, is not. Without the route the loop reports that residual and tries nothing; with it, the
// round looks, and the planted effect is the one found.
TEST(CalibrationSynthetic, TheHeldOutRouteTracesAResidualOnlyTheHeldOutPointsShow) {
  const SyntheticCase twin{.twin_seed = 6, .model_seed = 106, .shallow_held_out = true};
  TempDir off_dir("gapflow_calibration_synthetic_route_off");
  const SyntheticRun off = calibrate_synthetic(off_dir, {"rolling_resistance=0.008"}, 1, twin);
  EXPECT_GE(off.result.before.fitted.chi.p, 0.05) << "the premise: the fitted points within the noise";
  EXPECT_TRUE(off.result.effects.empty()) << off.log;
  EXPECT_EQ(off.result.verdict, "unexplained residual: the held-out points are beyond the noise");

  SyntheticCase with_route = twin;
  with_route.held_out_route = true;
  TempDir on_dir("gapflow_calibration_synthetic_route_on");
  const SyntheticRun on = calibrate_synthetic(on_dir, {"rolling_resistance=0.008"}, 1, with_route);
  EXPECT_NE(on.log.find("but the held-out points are not (fresh seeds"), std::string::npos) << on.log;
  ASSERT_EQ(on.result.effects.size(), 1u) << on.log;
  EXPECT_EQ(on.result.effects.front().effect, "rolling_resistance");
  EXPECT_LE(on.result.effects.front().lo95, 0.008);
  EXPECT_GE(on.result.effects.front().hi95, 0.008);
  // "effect found"; with the responses' cubic (801989a) the fresh-seed re-score leaves this twin's
  // held-out points just beyond the noise, and the verdict says so (before it: "effect found").
  EXPECT_EQ(on.result.verdict.rfind("effect found", 0), 0u) << on.result.verdict;
}

// The route keeps rule 1's condition on the candidate. On a null twin whose fitted points pass and
// whose held-out points do not, the route considers the round, no candidate's score is significant,
// and nothing is tried or added. Such twins are rare now: of twin seeds 1-30 of this design, only
// seed 16. Until the surface counted the noise its nodes share (calibrate/node_correlation.hpp; the
// closed-form model's replicates correlate about +0.9 between neighbouring nodes, which the surface
// had understated about 2x) seeds 12 and 16 were; until it weighted its nodes alike, 5 and 6 of 1-8.
// (A null on which a candidate is significant too, where the keep test would have to reject, was not
// found among these seeds.)
TEST(CalibrationSynthetic, TheHeldOutRouteTriesNothingOnANullTwinWithoutASignificantCandidate) {
  for (std::uint64_t seed : {16u}) {
    TempDir dir("gapflow_calibration_synthetic_route_null");
    const SyntheticRun run = calibrate_synthetic(
        dir, {}, 1, {.twin_seed = seed, .model_seed = 100 + seed, .shallow_held_out = true, .held_out_route = true});
    EXPECT_GE(run.result.before.fitted.chi.p, 0.05) << "the premise: the fitted points within the noise";
    EXPECT_NE(run.log.find("the held-out points are not consistent with the noise"), std::string::npos)
        << "the premise: the route considered this twin\n" << run.log;
    EXPECT_EQ(run.log.find(") tried"), std::string::npos) << run.log;
    EXPECT_TRUE(run.result.effects.empty()) << run.log;
  }
}

// Without noise the loop is unbiased: a planted drag comes back within 1.5 % and the friction at its
// truth (2.974 for 3 at e174dde; 2.961 with the response's variance counting every size the cubic
// leans on: its standard error is larger between sizes than at them, 17 % at 3 deg on the tilt's
// quadratic through 0, 2, 4, 6 deg, and without noise the deviance's 2 ln sigma term, which then
// decides, draws the fit toward a measured size). Blind passes 9-13 missed 31 of their recovered
// sizes' intervals, every one toward neutral; this says the cause is not in the fit's structure
// (surface, response interpolation, re-measurement). With the model's noise,
// SizeBiasAgainstModelNoise (below) finds a pull of about 3-4 % over 24 twins
// (calibrate/README.md, "Why sizes come out toward neutral").
TEST(CalibrationSynthetic, WithoutNoiseAPlantedDragIsRecoveredWithinOneAndAHalfPercent) {
  const NoiseScope quiet({1e-4, 1e-4});
  TempDir dir("gapflow_calibration_synthetic_noiseless");
  const SyntheticRun run = calibrate_synthetic(dir, {"linear_drag=3"}, 1);
  ASSERT_EQ(run.result.effects.size(), 1u) << run.log;
  EXPECT_EQ(run.result.effects.front().effect, "linear_drag");
  EXPECT_NEAR(run.result.effects.front().value, 3.0, 0.045) << run.log;
  EXPECT_NEAR(friction(run.result.after), 0.3, 0.002);
}

// The fitted response of the first round's effect is measured against the baseline's runs, all its
// sizes paired alike: with the signatures on seeds of their own it is measured anew (the step and
// its refinement, four sizes for drag), with shared signatures the signature's step is kept and
// the other sizes added (blind pass 20's rolling-high had sizes paired both ways, and a false well).
TEST(CalibrationSynthetic, TheFirstEffectsResponseIsMeasuredAgainstTheBaselinesRuns) {
  for (const bool own : {true, false}) {
    TempDir dir(own ? "gapflow_calibration_synthetic_pairing_own" : "gapflow_calibration_synthetic_pairing_shared");
    const SyntheticRun run = calibrate_synthetic(dir, {"linear_drag=3"}, 1, {.independent_signatures = own});
    ASSERT_EQ(run.result.effects.size(), 1u) << run.log;
    std::string sizes;
    bool own_signatures = false;  // the premise: the signatures ran on seeds of their own exactly when asked
    for (const std::string& line : run.result.log) {
      if (line.rfind("linear_drag: response measured at", 0) == 0 && sizes.empty()) sizes = line;
      own_signatures |= line.rfind("signatures on seeds of their own", 0) == 0;
    }
    ASSERT_FALSE(sizes.empty()) << run.log;
    EXPECT_EQ(own_signatures, own) << run.log;
    EXPECT_NE(sizes.find(own ? "response measured at 4 size(s) (1, 2, 4, 6)" : "response measured at 3 more size(s) (1, 4, 6)"),
              std::string::npos)
        << sizes;
  }
}

// Which runs a term's shifts are paired with (EffectTerm::paired_with), which is how the surface
// knows the noise a first effect shares with its quadratic (fit.hpp, Surface::predict): the
// baseline reference's nodes, whose runs the quadratic goes through; none where the signatures ran
// on seeds of their own. More sizes measured against other runs than a term's first ones are refused.
TEST(CalibrationSynthetic, ATermRecordsTheRunsItsShiftsArePairedWith) {
  TempDir dir("gapflow_calibration_synthetic_paired_with");
  write_design(dir / "design.toml", 4, 1);
  TwinDef twin;
  twin.seed = 3;
  twin.effects = {"linear_drag=3"};
  (void)make_synthetic_twin(dir, twin);
  const DataFile data = load_data_file(dir / "twin.toml");
  EvaluatorOptions eo;
  eo.runner = run_synthetic;
  Store store(dir / "cal.sqlite");
  Evaluator ev(data, store, eo);
  const CalibrationDef def;
  const Say quiet = [](const std::string&) {};
  const BaselineFit base = fit_baseline(data, def, ev, quiet);
  EffectResponses responses(data, def, ev, quiet);
  const Reference baseline = EffectResponses::baseline_reference(base);
  const auto labels = [](const std::vector<ParameterSet>& sets) {
    std::vector<std::string> out;
    for (const ParameterSet& p : sets) out.push_back(p.label());
    return out;
  };
  ASSERT_EQ(base.nodes.size(), 3u);
  std::vector<EffectTerm> shared, own;
  const std::vector<Candidate> cands = responses.signatures(baseline, shared);
  (void)responses.signatures(responses.on_own_seeds(baseline, data.seed + 1000), own);
  ASSERT_EQ(shared.size(), own.size());
  for (std::size_t k = 0; k < shared.size(); ++k) {
    EXPECT_EQ(labels(shared[k].paired_with), labels(base.nodes)) << shared[k].effect;
    EXPECT_TRUE(own[k].paired_with.empty()) << own[k].effect;
  }
  const auto drag = static_cast<std::size_t>(
      std::find_if(cands.begin(), cands.end(), [](const Candidate& c) { return c.effect == "linear_drag"; }) - cands.begin());
  ASSERT_LT(drag, cands.size());
  EXPECT_EQ(labels(responses.measure_term(cands[drag], baseline).paired_with), labels(base.nodes));
  EXPECT_THROW(responses.refine(own[drag], cands[drag], baseline), std::logic_error);
}

// Exploration (disabled: about 16 s a twin): how often the form check flags a drag of the
// catalogue's own form (a false alarm) or of another form (quadratic in the speed), over twins of
// the 15-point design. GAPFLOW_SEEDS twins (default 8, seeds 3 on), GAPFLOW_PLANTED
// ("linear_drag=4" or a quadratic drag's "particles.quadratic_drag_per_m=1.5"),
// GAPFLOW_MODEL_REPLICATES (default 16). Prints each twin's verdict and the count flagged.
//   GAPFLOW_PLANTED=linear_drag=4 build/tests/gapflow_tests --gtest_also_run_disabled_tests --gtest_filter='*FormCheckRates*'
TEST(CalibrationSynthetic, DISABLED_FormCheckRates) {
  const auto seeds = static_cast<std::uint64_t>(knob("GAPFLOW_SEEDS", 8));
  const std::string planted = text_knob("GAPFLOW_PLANTED", "linear_drag=4");
  const bool outside = planted.rfind("particles.", 0) == 0;
  int flagged = 0, added = 0;
  for (std::uint64_t seed = 3; seed < 3 + seeds; ++seed) {
    TempDir dir("gapflow_form_rates");
    SyntheticCase c;
    c.twin_seed = seed;
    c.more_gaps = true;
    c.model_replicates = static_cast<int>(knob("GAPFLOW_MODEL_REPLICATES", 16));
    if (outside) c.outside = {planted};
    const SyntheticRun run = calibrate_synthetic(dir, outside ? std::vector<std::string>{} : std::vector<std::string>{planted}, 1, c);
    added += !run.result.effects.empty();
    flagged += run.result.form_differs;
    std::cout << "twin " << seed << ": " << run.result.verdict << "\n";
  }
  std::cout << planted << ": an effect added in " << added << " of " << seeds << ", flagged by the form check in "
            << flagged << "\n";
}

// Exploration, not run by default (prints; asserts nothing): the recovered size of a planted drag of
// 3 /s over twin seeds, with the model's noise mostly of each parameter value's own, as the
// simulator's is (trajectories part within a few collisions). Knobs: GAPFLOW_COMMON_NOISE,
// GAPFLOW_OWN_NOISE (sd on ln J; default 0.005, 0.03), GAPFLOW_OWN_NOISE_IN (all, drag or drag-free:
// which runs carry the own part; default all), GAPFLOW_MODEL_REPS (model runs per point, default 4),
// GAPFLOW_SEEDS (twins, default 8), GAPFLOW_MODEL_SEED (fixed: the calibration's model runs on base
// seed 1 for every twin, so the twins share one draw of the model's noise; per-twin: seed 100 + the
// twin's: each twin its own draw of the model's noise, what a bias needs; default per-twin).
// calibrate/README.md, "Why sizes come out toward neutral": the numbers it gave.
//   GAPFLOW_SEEDS=3 build/tests/gapflow_tests --gtest_also_run_disabled_tests --gtest_filter='*SizeBias*'
TEST(CalibrationSynthetic, DISABLED_SizeBiasAgainstModelNoise) {
  const std::string own_in = text_knob("GAPFLOW_OWN_NOISE_IN", "all");
  ASSERT_TRUE(own_in == "all" || own_in == "drag" || own_in == "drag-free") << "GAPFLOW_OWN_NOISE_IN: all, drag or drag-free";
  const NoiseScope noise({knob("GAPFLOW_COMMON_NOISE", 0.005), knob("GAPFLOW_OWN_NOISE", 0.03),
                          own_in == "all"    ? NoiseLevels::OwnIn::all
                          : own_in == "drag" ? NoiseLevels::OwnIn::drag_runs
                                             : NoiseLevels::OwnIn::drag_free_runs});
  const int reps = static_cast<int>(knob("GAPFLOW_MODEL_REPS", 4));
  const auto seeds = static_cast<std::uint64_t>(knob("GAPFLOW_SEEDS", 8));
  const std::string model_seed = text_knob("GAPFLOW_MODEL_SEED", "per-twin");
  ASSERT_TRUE(model_seed == "fixed" || model_seed == "per-twin") << "GAPFLOW_MODEL_SEED: fixed or per-twin";
  std::cout << fmt::format("noise common {} own {} ({} runs) on ln J, {} model runs per point, model seed {}\n",
                           g_noise.common, g_noise.own, own_in, reps, model_seed);
  for (std::uint64_t seed = 1; seed <= seeds; ++seed) {
    TempDir dir("gapflow_calibration_synthetic_bias");
    const SyntheticCase c{.twin_seed = seed, .model_replicates = reps, .model_seed = model_seed == "fixed" ? 1 : 100 + seed};
    const CalibrationResult r = calibrate_synthetic(dir, {"linear_drag=3"}, 1, c).result;
    std::string sizes;
    for (const AddedEffect& e : r.effects) sizes += fmt::format("{} {:.3f} [{:.3f}, {:.3f}] ", e.effect, e.value, e.lo95, e.hi95);
    std::cout << fmt::format("seed {}: {}friction {:.3f}; chi2/nu after {:.2f}\n", seed, sizes, friction(r.after),
                             r.after.fitted.chi.per_dof());
  }
}

// Exploration, not run by default (prints; asserts nothing): how often the 95 % interval of a planted
// effect holds its size when part of the effect's response is a level the particle friction can take
// up, and the friction is measured beside the data (as design v2's, se 0.04). Blind passes 19-21 and
// 23 read spinning friction at a median 0.45 of its planted size, 2 of 5 intervals holding it
// (results/calibration-interval-coverage/; this exploration's counts in its closed-form/, run.sh).
// Knobs: GAPFLOW_EFFECT (default spinning_friction; a catalogue spec as `gapflow twin --effect`
// takes), GAPFLOW_SPIN_LEVEL (g_spin_level, default 0.15), GAPFLOW_SPIN_COUPLING (g_spin_coupling,
// default 0), GAPFLOW_FRICTION_SE (default 0.04; 0: no measurement), GAPFLOW_COMMON_NOISE,
// GAPFLOW_OWN_NOISE (default 0.005, 0.03), GAPFLOW_MODEL_REPS (default 6), GAPFLOW_SEEDS (twins,
// default 20), GAPFLOW_MORE_GAPS (default 1: 15 fitted points). Each twin draws its friction in
// 0.18-0.42 and calibrates against its own draw of the model's noise (model seed 100 + its seed).
//   build/tests/gapflow_tests --gtest_also_run_disabled_tests --gtest_filter='*IntervalCoverageAgainst*'
TEST(CalibrationSynthetic, DISABLED_IntervalCoverageAgainstTheFriction) {
  const NoiseScope noise({knob("GAPFLOW_COMMON_NOISE", 0.005), knob("GAPFLOW_OWN_NOISE", 0.03)});
  const SpinLevelScope level(knob("GAPFLOW_SPIN_LEVEL", 0.15));
  const SpinCouplingScope coupling(knob("GAPFLOW_SPIN_COUPLING", 0));
  const std::string spec = text_knob("GAPFLOW_EFFECT", "spinning_friction");
  const std::string effect = spec.substr(0, spec.find_first_of(":="));
  const int reps = static_cast<int>(knob("GAPFLOW_MODEL_REPS", 6));
  const auto seeds = static_cast<std::uint64_t>(knob("GAPFLOW_SEEDS", 20));
  const double measured_se = knob("GAPFLOW_FRICTION_SE", 0.04);
  const bool more_gaps = knob("GAPFLOW_MORE_GAPS", 1) != 0;
  std::cout << fmt::format(
      "{} with level {} ln J/mm (coupling {}); friction measured se {}; noise common {} own {}; {} model runs per point\n", spec,
      g_spin_level, g_spin_coupling, measured_se, g_noise.common, g_noise.own, reps);
  int sized = 0, held = 0;
  std::vector<double> read_over_planted;
  for (std::uint64_t seed = 1; seed <= seeds; ++seed) {
    TempDir dir("gapflow_calibration_synthetic_coverage");
    write_design(dir / "design.toml", reps, 100 + seed, false, more_gaps, measured_se);
    TwinDef twin;
    twin.seed = seed;
    twin.effects = {spec};
    const TwinTruth truth = make_synthetic_twin(dir, twin);
    double planted = 0, true_friction = 0;
    for (const PlantedValue& v : truth.planted) {
      if (v.name == "free") true_friction = v.value;
      if (v.name == effect) planted = v.value;
    }
    CalibrationDef def;
    def.alternatives = 0;  // changes no size (AlternativesThatAloneFit... above); saves the fits
    const CalibrationResult r = calibrate_synthetic_twin(dir, def);
    std::string line = fmt::format("seed {:2}: planted {:.3f}, friction {:.3f} measured {:.3f} fitted {:.3f}; ", seed, planted,
                                   true_friction, truth.measured.empty() ? kNaN : truth.measured.front(), friction(r.after));
    bool found = false;
    for (const AddedEffect& e : r.effects) {
      line += fmt::format("{} {:.3f} [{:.3f}, {:.3f}] ", e.effect, e.value, e.lo95, e.hi95);
      if (e.effect != effect) continue;
      found = true;
      ++sized;
      held += e.lo95 <= planted && planted <= e.hi95;
      read_over_planted.push_back((e.value - e.neutral) / (planted - e.neutral));
    }
    std::cout << line << (found ? "" : "(not found) ") << r.verdict << "\n";
  }
  std::cout << fmt::format("{}: found in {} of {}; interval holds the planted size in {} of {}; read/planted median {:.2f}\n",
                           effect, sized, seeds, held, sized, median(read_over_planted));
}

// The first round's scores on null twins lean toward each effect's step when the signatures are
// measured against the baseline nodes' own runs: the residual and the signature then share those
// runs' noise (effect_responses.hpp, "Shared noise"). On seeds of their own they do not. The noise
// here is mostly each parameter value's own, as the simulator's (DISABLED_NullScores below: over 20
// null twins, z toward the step +1.08 on the baseline's seeds, estimates toward it 79 of 93, best
// adjusted p < 0.05 in 5; on their own seeds +0.05, 39 of 86, 1).
double mean_z_toward_step(bool independent_signatures, int& scored) {
  const NoiseScope noise({0.005, 0.03});
  double sum = 0;
  scored = 0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    TempDir dir("gapflow_calibration_synthetic_null_lean");
    const SyntheticCase c{.twin_seed = seed, .model_seed = 100 + seed, .independent_signatures = independent_signatures};
    const CalibrationResult r = calibrate_synthetic(dir, {}, 1, c).result;
    if (r.rounds.empty()) continue;
    for (const Candidate& k : r.rounds.front().candidates) {
      if (!k.visible) continue;
      sum += z_toward_step(k);
      ++scored;
    }
  }
  return scored ? sum / scored : 0.0;
}

TEST(CalibrationSynthetic, SignaturesOnSeedsOfTheirOwnRemoveTheScoresLeanOnNullTwins) {
  int n_shared = 0, n_own = 0;
  const double shared = mean_z_toward_step(false, n_shared);
  const double own = mean_z_toward_step(true, n_own);
  ASSERT_GE(n_shared, 10);
  ASSERT_GE(n_own, 10);
  EXPECT_GT(shared, 0.6) << "the premise: on the baseline's seeds the scores lean toward the step";
  EXPECT_LT(std::abs(own), 0.4) << "mean z over " << n_own << " scores";
  std::cout << fmt::format("mean z toward the step: baseline seeds {:.3f} ({} scores), own seeds {:.3f} ({})\n", shared,
                           n_shared, own, n_own);
}

// Exploration, not run by default (prints; asserts nothing): the first round's scores on null twins,
// with the signatures on the baseline's seeds and on seeds of their own (effect_responses.hpp,
// "Shared noise"). Knobs as SizeBiasAgainstModelNoise's: GAPFLOW_COMMON_NOISE, GAPFLOW_OWN_NOISE
// (default 0.005, 0.03: mostly each parameter value's own, as the simulator's), GAPFLOW_MODEL_REPS
// (default 4), GAPFLOW_SEEDS (default 20).
//   GAPFLOW_SEEDS=20 build/tests/gapflow_tests --gtest_also_run_disabled_tests --gtest_filter='*NullScores*'
TEST(CalibrationSynthetic, DISABLED_NullScores) {
  const NoiseScope noise({knob("GAPFLOW_COMMON_NOISE", 0.005), knob("GAPFLOW_OWN_NOISE", 0.03)});
  const int reps = static_cast<int>(knob("GAPFLOW_MODEL_REPS", 4));
  const auto seeds = static_cast<std::uint64_t>(knob("GAPFLOW_SEEDS", 20));
  for (bool own : {false, true}) {
    int below_05 = 0, below_01 = 0, toward = 0, scored = 0;
    double sum_z = 0;
    for (std::uint64_t seed = 1; seed <= seeds; ++seed) {
      TempDir dir("gapflow_calibration_synthetic_null_scores");
      const SyntheticCase c{.twin_seed = seed, .model_replicates = reps, .model_seed = 100 + seed,
                            .independent_signatures = own};
      const CalibrationResult r = calibrate_synthetic(dir, {}, 1, c).result;
      if (r.rounds.empty()) continue;
      double best = 1;
      std::string line;
      for (const Candidate& k : r.rounds.front().candidates) {
        if (!k.visible) continue;
        best = std::min(best, k.p_adjusted);
        const bool lean = k.score.estimate * k.step > 0;
        toward += lean;
        ++scored;
        sum_z += z_toward_step(k);
        line += fmt::format(" {} {:+.3g} (p adj {:.3g})", k.effect, k.score.estimate / k.step, k.p_adjusted);
      }
      below_05 += best < 0.05, below_01 += best < 0.01;
      std::cout << fmt::format("{} seed {}: chi2 p {:.3g};{}\n", own ? "own seeds" : "baseline seeds", seed,
                               r.before.fitted.chi.p, line);
    }
    std::cout << fmt::format("{}: best adjusted p < 0.05 in {} of {}, < 0.01 in {}; estimates toward the step {} of {}; "
                             "mean z toward the step {:.3f}\n",
                             own ? "OWN SEEDS" : "BASELINE SEEDS", below_05, seeds, below_01, toward, scored,
                             scored ? sum_z / scored : 0.0);
  }
}

}  // namespace
}  // namespace gapflow
