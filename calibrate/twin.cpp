#include "calibrate/twin.hpp"

#include "calibrate/calibration.hpp"
#include "calibrate/effect_catalogue.hpp"
#include "calibrate/fit.hpp"
#include "common/random.hpp"
#include "common/statistics.hpp"
#include "common/text_file.hpp"
#include "common/toml_spelling.hpp"
#include "common/toml_strict.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

namespace gapflow {

namespace {

// A size in the effect's plausible range, on the side its step points to:
// "low" 35-60 % and "high" 70-100 % of the way from the neutral value to the range's end.
double drawn_size(const EffectDef& e, double neutral, const std::string& size, RandomStream& rng) {
  const double end = e.step > 0 ? e.hi : e.lo;
  double f = rng.uniform(0.35, 1.0);
  if (size == "low") f = rng.uniform(0.35, 0.6);
  if (size == "high") f = rng.uniform(0.7, 1.0);
  return neutral + f * (end - neutral);
}

void write_twin_file(std::ostream& o, const DataFile& d, const TwinDef& def, const TwinTruth& truth, const Prediction& p,
                     const std::filesystem::path& data_out) {
  o << "# Made by `gapflow twin` from " << d.file.string() << ": simulated data for testing the calibration loop.\n";
  o << "# What was planted is in the truth file, never here.\n\n";
  o << fmt::format("[data]\nname = {}\ndescription = {}\n\n", toml_quote(def.name),
                   toml_quote("twin of " + d.name + " (" + to_string(def.model) + " model)"));
  o << fmt::format("[source]\ncitation = {}\nmethod = \"simulated\"\nuncertainty = {}\n\n",
                   toml_quote(fmt::format("gapflow twin, {} model, seed {}", to_string(def.model), def.seed)),
                   toml_quote(fmt::format("standard error of the mean of {} runs per point", def.replicates)));
  const std::filesystem::path rel = std::filesystem::relative(std::filesystem::absolute(d.scenario),
                                                              std::filesystem::absolute(data_out).parent_path());
  o << fmt::format("[model]\nscenario = {}\nset = [", toml_quote(rel.generic_string()));
  for (std::size_t i = 0; i < d.set.size(); ++i) o << (i ? ", " : "") << toml_quote(d.set[i]);
  o << fmt::format("]\nreplicates = {}\nseed = {}\n\n", d.model_replicates, def.model_seed.value_or(d.seed));
  o << fmt::format("[observable]\nkind = \"{}\"\nscale = \"{}\"\nuncertainty = \"se\"\nfloor_relative = {}\n\n",
                   to_string(d.observable), d.scale == FitScale::log ? "log" : "linear", number_text(d.floor_relative));
  if (!d.floors.empty()) o << "[floors]\n";
  for (const auto& [kind, floor] : d.floors)
    o << fmt::format("{} = {{ relative = {}, absolute = {} }}\n", to_string(kind), number_text(floor.relative),
                     number_text(floor.absolute));
  if (!d.floors.empty()) o << "\n";
  for (const DesignColumn& c : d.design)
    o << fmt::format("[[design]]\ncolumn = {}\nkey = {}\nunit = \"{}\"\n\n", toml_quote(c.column), toml_quote(c.key),
                     c.in_diameters ? "d" : "lab");
  for (std::size_t k = 0; k < d.free.size(); ++k) {
    const FreeParameter& f = d.free[k];
    o << fmt::format("[[free]]\nkey = {}\nlo = {}\nhi = {}\nstep = {}\n", toml_quote(f.key), number_text(f.lo),
                     number_text(f.hi), number_text(f.step));
    if (f.has_measurement() && k < truth.measured.size() && std::isfinite(truth.measured[k]))
      o << fmt::format("measured = {}\nmeasured_se = {}\n", number_text(truth.measured[k]), number_text(f.measured_se));
    o << "\n";
  }
  for (std::size_t i = 0; i < d.points.size(); ++i) {
    if (!p.valid[i])
      throw std::runtime_error(fmt::format("twin: the model gives no {} at point {} (e.g. a run never emptied)",
                                           to_string(d.points[i].observable), d.point_label(i)));
    const double se = d.points[i].scale == FitScale::log ? p.se_fit[i] * p.value[i] : p.se_fit[i];
    o << "[[point]]\n";
    for (std::size_t c = 0; c < d.design.size(); ++c) o << toml_key(d.design[c].column) << " = " << d.points[i].design[c] << "\n";
    if (d.points[i].observable != d.observable) o << "observable = \"" << to_string(d.points[i].observable) << "\"\n";
    o << fmt::format("value = {}\nuncertainty = {}\nreplicates = {}\nheld_out = {}\n\n", number_text(p.value[i]),
                     number_text(se), def.replicates, d.points[i].held_out ? "true" : "false");
  }
}

// The planted values replaced by what the design's template has without them;
// the free parameters keep their true values.
ParameterSet without_planted_effects(const DataFile& design, const TwinTruth& truth) {
  ParameterSet out;
  for (const PlantedValue& v : truth.planted)
    out = out.with(v.key, v.name == "free" ? v.value : template_value(v.key, design));
  return out;
}

// The noise a calibration of the twin sees at point i, on the fit scale: the twin
// file's se (a standard error `se` of the mean of def.replicates runs, with the design's
// floor) and the model's as the loop sees it, `model_se` (loop_model_se).
double calibration_sigma(const DataFile& design, const Prediction& with, std::size_t i, double se, double model_se) {
  const SeFloor f = design.floor_of(design.points[i].observable);
  const double value = std::abs(with.value[i]);
  const double floor = std::hypot(f.relative * value, f.absolute);  // in the observable's unit
  return std::hypot(std::hypot(se, design.points[i].scale == FitScale::log ? floor / value : floor), model_se);
}

// The run-to-run standard error at each point from the model's runs at every grid node
// (mean of their se^2): an estimate of the noise with ~9 x 10 runs behind it and nearly
// independent of any one pair compared. The twin's own se would not do: its 10 runs are
// also in the paired variance subtracted, and the two estimates move together.
std::vector<double> pooled_se(const std::vector<Prediction>& nodes, std::size_t points) {
  std::vector<double> se(points, 0.0);
  for (std::size_t i = 0; i < points; ++i) {
    double sum = 0;
    int n = 0;
    for (const Prediction& q : nodes)
      if (q.valid[i] && std::isfinite(q.se_fit[i])) sum += q.se_fit[i] * q.se_fit[i], ++n;
    se[i] = n > 0 ? std::sqrt(sum / n) : std::numeric_limits<double>::quiet_NaN();
  }
  return se;
}

// Variance of the mean paired difference at point i: the spread of with - without over the
// replicates both have (same seeds), over their number. 0 with fewer than two pairs.
double paired_difference_variance(const Prediction& with, const Prediction& without, std::size_t i) {
  std::vector<double> d;
  const std::size_t n = std::min(with.replicate_fit[i].size(), without.replicate_fit[i].size());
  for (std::size_t r = 0; r < n; ++r) {
    const double a = with.replicate_fit[i][r], b = without.replicate_fit[i][r];
    if (std::isfinite(a) && std::isfinite(b)) d.push_back(a - b);
  }
  if (d.size() < 2) return 0.0;
  const Summary s = summarize(d);
  return s.se() * s.se();
}

// The minimum over the friction grid of node values that each carry noise (sd ~6 on the
// blind design): the smallest node alone is biased low (it is the luckiest of several), so
// a parabola is fitted by least squares through the five nodes around it (equally spaced;
// moved inward at the grid's ends) and its minimum taken inside them.
double smoothed_minimum(const std::vector<double>& y, std::size_t best) {
  // five nodes around the best, moved inward at the grid's ends (fewer only on a short grid)
  const std::size_t width = std::min<std::size_t>(5, y.size());
  const std::size_t lo = std::min(best >= 2 ? best - 2 : 0, y.size() - width), hi = lo + width - 1;
  std::vector<double> xs, ys;
  for (std::size_t k = lo; k <= hi; ++k)
    if (std::isfinite(y[k])) xs.push_back(static_cast<double>(k)), ys.push_back(y[k]);
  if (xs.size() < 3) return y[best];
  Eigen::MatrixXd A(static_cast<Eigen::Index>(xs.size()), 3);
  Eigen::VectorXd b(static_cast<Eigen::Index>(xs.size()));
  for (std::size_t k = 0; k < xs.size(); ++k) {
    const auto r = static_cast<Eigen::Index>(k);
    A(r, 0) = 1, A(r, 1) = xs[k], A(r, 2) = xs[k] * xs[k];
    b(r) = ys[k];
  }
  const Eigen::Vector3d c = A.colPivHouseholderQr().solve(b);
  const auto at = [&](double x) { return c(0) + c(1) * x + c(2) * x * x; };
  double m = std::min(at(xs.front()), at(xs.back()));
  if (c(2) > 0) {
    const double vertex = -c(1) / (2 * c(2));
    if (vertex > xs.front() && vertex < xs.back()) m = std::min(m, at(vertex));
  }
  return m;
}

// lambda = min over the free parameter of planted_noncentrality (plus, where the twin carries a
// reading of it, that measurement's chi^2 about the true value): how far the data with the
// planted effects lie from everything the model without them can reach by refitting
// (the nonlinear projection; friction saturates, so a linear one overstates lambda).
// One free parameter: its calibration grid, smoothed by a least-squares parabola around
// the best node (smoothed_minimum). Several: their true values only (an upper bound, said so).
PlantedSignal planted_signal(const DataFile& design, const TwinDef& def, const TwinTruth& truth, const Prediction& with,
                             Evaluator& ev) {
  PlantedSignal sig;
  const bool any_effect = std::any_of(truth.planted.begin(), truth.planted.end(),
                                      [](const PlantedValue& v) { return v.name != "free"; });
  if (!any_effect) return sig;
  const ParameterSet without = without_planted_effects(design, truth);
  std::vector<ParameterSet> sets;
  if (design.free.size() == 1) {
    const FreeParameter& f = design.free.front();  // the calibration's own grid (same job keys)
    for (double v : grid_levels(f, true, CalibrationDef{}.grid_max)) sets.push_back(without.with(f.key, v));
  } else {
    sets.push_back(without);
  }
  const std::vector<Prediction> p = ev.evaluate(sets, truth.model_seed, def.replicates);
  const std::vector<double> se = pooled_se(p, design.points.size());
  const auto noncentralities = [&](const std::vector<double>& model_se) {
    std::vector<double> out;
    for (const Prediction& q : p) out.push_back(planted_noncentrality(design, with, q, se, model_se));
    return out;
  };
  // The loop's model noise depends on where its surface is centred: centre it on the node
  // nearest the refit that a raw model noise gives, then refit with the loop's noise.
  std::vector<double> chi2 = noncentralities(raw_model_se(design, def, se));
  if (design.free.size() == 1) {
    const auto near = static_cast<std::size_t>(std::min_element(chi2.begin(), chi2.end()) - chi2.begin());
    chi2 = noncentralities(loop_model_se(design, def, sets, p, near));
  }
  // A measured free parameter is a datum of the calibration's refit: the oracle's refit pays for
  // moving it away from its true value (where the reading lies in expectation) as the loop pays
  // for moving it from the reading.
  // Only where the twin carries a reading (its free parameter's true value was drawn or set).
  if (design.free.size() == 1 && !truth.measured.empty() && std::isfinite(truth.measured.front())) {
    const FreeParameter& f = design.free.front();
    for (const PlantedValue& v : truth.planted)
      if (v.name == "free" && v.key == f.key)
        for (std::size_t k = 0; k < sets.size(); ++k) chi2[k] += std::pow((sets[k].get(f.key, v.value) - v.value) / f.measured_se, 2);
  }
  const std::size_t best = static_cast<std::size_t>(std::min_element(chi2.begin(), chi2.end()) - chi2.begin());
  if (!std::isfinite(chi2[best])) return sig;  // no node gives every point a value: nothing to compare
  sig.chi2 = std::max(0.0, smoothed_minimum(chi2, best));
  for (std::size_t i = 0; i < design.points.size(); ++i) sig.points += !design.points[i].held_out && with.valid[i] ? 1 : 0;
  int candidates = 0;
  for (const EffectDef& e : effect_catalogue()) candidates += effect_applies(e, def.model, design) ? 1 : 0;
  // Bonferroni over every applicable effect: the loop divides by the visible ones only,
  // so this threshold is conservative (the power a lower bound).
  const double alpha = CalibrationDef{}.alpha / std::max(1, candidates);
  sig.known = true;
  sig.critical = chi_square_quantile(1 - alpha, 1);
  // Score statistic ~ (Z + sqrt(lambda))^2 for a known signature: noncentral chi^2_1.
  const double a = std::sqrt(sig.critical), b = std::sqrt(sig.chi2);
  sig.oracle_power = normal_cdf(-a - b) + 1 - normal_cdf(a - b);
  return sig;
}

// A number given on the command line (--set key=VALUE, --effect NAME=VALUE): all of it must be
// a finite number, else the user is told which option and what was given.
double option_number(const std::string& text, const std::string& option) {
  double v = 0;
  const char* end = text.data() + text.size();
  const auto [stop, ec] = std::from_chars(text.data(), end, v);
  if (text.empty() || ec != std::errc() || stop != end || !std::isfinite(v))
    throw std::invalid_argument(fmt::format("twin: {}: '{}' is not a number", option, text));
  return v;
}

}  // namespace

// The planted effects' noncentrality over the fitted points: the twin's data against the
// model without the effects, both on the twin's seeds, in units of the noise a calibration
// sees. Same seeds do not make the difference noise-free: any parameter change parts the
// trajectories of a granular flow within a few collisions, after which the paired runs are
// as independent as any two. So the paired difference's own variance (from the spread of the
// replicate differences) is subtracted: what is left estimates signal^2, unbiased, and is
// what a score test that knew the signature would see beyond the noise (an effect the model
// barely feels gives ~0 here, not n_points x the decorrelation noise).
// Infinite where the model without the effects gives no value at some point (a node
// that cannot be compared, rather than a made-up penalty the refinement would bend to).
double planted_noncentrality(const DataFile& design, const Prediction& with, const Prediction& without,
                             const std::vector<double>& se, const std::vector<double>& model_se) {
  double chi2 = 0;
  for (std::size_t i = 0; i < design.points.size(); ++i) {
    if (design.points[i].held_out || !with.valid[i]) continue;
    if (!without.valid[i]) return std::numeric_limits<double>::infinity();
    const double d = with.fit[i] - without.fit[i];
    const double sigma = calibration_sigma(design, with, i, se[i], model_se[i]);
    if (!(sigma > 0)) continue;  // no noise and no floor: nothing to measure the difference in
    chi2 += (d * d - paired_difference_variance(with, without, i)) / (sigma * sigma);
  }
  return chi2;  // below 0 where the noise outweighs the signal: the caller clamps after smoothing
}

// The model's part of the noise as a raw grid node shows it: the standard error of a mean of
// the design's model replicates, from `se` (a mean of def.replicates runs). Also the scaling of
// loop_model_se's surface noise, built from means of def.replicates runs.
std::vector<double> raw_model_se(const DataFile& design, const TwinDef& def, const std::vector<double>& se) {
  const double model_share = static_cast<double>(def.replicates) / design.model_replicates;
  std::vector<double> out;
  for (double s : se) out.push_back(s * std::sqrt(model_share));
  return out;
}

// The model's part of the noise as the loop sees it. The loop does not compare the data with a
// raw grid node: its fit, its residual and its score test all use the response surface through
// the five nodes around the fit (fit.cpp, surface_around), a least-squares quadratic whose
// prediction is less noisy than any one node (at the middle of five independent nodes of equal noise,
// by sqrt(17/35); less so where they share their seeds' error, calibrate/node_correlation.hpp), and
// whose noise is what it whitens with. Before, the oracle took the raw node's
// noise and so understated what the loop sees (passes 8-14: the loop's baseline chi^2 beyond its
// degrees of freedom ran 1.29 x the oracle's lambda, median over 114 twins;
// results/calibration-blind-passes.md, "The oracle's noise"). The same surface is built here
// from the oracle's nodes (def.replicates runs each) around node `near`, and its standard error
// scaled to the design's model replicates.
std::vector<double> loop_model_se(const DataFile& design, const TwinDef& def, const std::vector<ParameterSet>& nodes,
                                  const std::vector<Prediction>& predictions, std::size_t near) {
  BaselineFit grid;
  grid.grid = nodes;
  grid.grid_predictions = predictions;
  return raw_model_se(design, def, surface_around(design, grid, nodes[near]).predict_fit(nodes[near]).se_fit);
}

TwinTruth draw_twin(const DataFile& design, const TwinDef& def) {
  TwinTruth t;
  RandomStream rng(mix_seed(def.seed, 0x7477696eull));  // "twin"
  t.model_seed = design.seed + 1000003 + def.seed;      // never the seeds a calibration of it uses
  // A --set of a free parameter's key is its true value (e.g. the material both models share):
  // still drawn, so that every other draw is the same with and without it, then replaced.
  const auto set_value = [&](const std::string& key) -> std::optional<double> {
    for (const std::string& s : def.set)
      if (s.rfind(key + "=", 0) == 0) return option_number(s.substr(key.size() + 1), "--set " + key);
    return std::nullopt;
  };
  if (def.draw_free)
    for (const FreeParameter& f : design.free) {
      const double span = f.hi - f.lo;
      const double drawn = rng.uniform(f.lo + 0.2 * span, f.hi - 0.2 * span);
      t.planted.push_back({"free", f.key, set_value(f.key).value_or(drawn), kNaN});
    }
  for (const std::string& spec : def.effects) {
    const std::size_t cut = spec.find_first_of(":=");
    const std::string name = spec.substr(0, cut);
    const EffectDef* e = find_effect(name);
    if (!e) throw std::invalid_argument("twin: '" + name + "' is not an effect of the catalogue");
    const double neutral = neutral_value(*e, design);
    double value = 0;
    if (cut != std::string::npos && spec[cut] == '=') {
      value = option_number(spec.substr(cut + 1), "--effect " + name);
      if (value < e->lo || value > e->hi)
        throw std::invalid_argument(fmt::format("twin: {} = {} is outside its plausible range [{}, {}]", name, value, e->lo, e->hi));
    } else {
      const std::string size = cut == std::string::npos ? "" : spec.substr(cut + 1);
      if (!size.empty() && size != "low" && size != "high")
        throw std::invalid_argument("twin: size '" + size + "' of " + name + " must be low or high");
      value = drawn_size(*e, neutral, size, rng);
    }
    t.planted.push_back({name, e->key, value, neutral});
  }
  // The measurements, from a stream of their own: every draw above is the same with and without them.
  RandomStream meter(mix_seed(def.seed, 0x6d65746572ull));  // "meter"
  for (const FreeParameter& f : design.free) {
    double truth_value = kNaN;
    for (const PlantedValue& v : t.planted)
      if (v.name == "free" && v.key == f.key) truth_value = v.value;
    const double read = truth_value + f.measured_se * meter.normal();
    t.measured.push_back(f.has_measurement() && std::isfinite(truth_value) ? read : kNaN);
  }
  for (const std::string& s : def.set) {
    const std::size_t eq = s.find('=');
    if (eq == std::string::npos) throw std::invalid_argument("twin: --set takes key=value, not '" + s + "'");
    const std::string key = s.substr(0, eq);
    if (std::any_of(t.planted.begin(), t.planted.end(), [&](const PlantedValue& v) { return v.name == "free" && v.key == key; }))
      continue;  // a free parameter's true value, recorded above
    t.planted.push_back({"set", key, option_number(s.substr(eq + 1), "--set " + key), kNaN});
  }
  return t;
}

TwinTruth make_twin(const DataFile& design, const TwinDef& def, Evaluator& evaluator,
                    const std::filesystem::path& data_out, const std::filesystem::path& truth_out) {
  TwinTruth truth = draw_twin(design, def);
  ParameterSet planted;
  for (const PlantedValue& v : truth.planted) planted = planted.with(v.key, v.value);
  const Prediction p = evaluator.evaluate({planted}, truth.model_seed, def.replicates).front();
  truth.signal = planted_signal(design, def, truth, p, evaluator);
  write_file_atomically(data_out, [&](std::ostream& o) { write_twin_file(o, design, def, truth, p, data_out); });
  write_file_atomically(truth_out, [&](std::ostream& o) {
    o << "{\n  \"twin\": \"" << def.name << "\",\n  \"model\": \"" << to_string(def.model) << "\",\n";
    o << fmt::format("  \"seed\": {},\n  \"model_seed\": {},\n  \"replicates\": {},\n  \"planted\": [", def.seed,
                     truth.model_seed, def.replicates);
    for (std::size_t i = 0; i < truth.planted.size(); ++i) {
      const PlantedValue& v = truth.planted[i];
      o << fmt::format("{}\n    {{\"name\": \"{}\", \"key\": \"{}\", \"value\": {}, \"neutral\": {}}}", i ? "," : "", v.name,
                       v.key, v.value, std::isfinite(v.neutral) ? fmt::format("{}", v.neutral) : "null");
    }
    o << "\n  ],\n  \"measured\": {";
    std::string sep;
    for (std::size_t k = 0; k < design.free.size() && k < truth.measured.size(); ++k)
      if (std::isfinite(truth.measured[k]))
        o << fmt::format("{}\"{}\": {}", sep, design.free[k].key, truth.measured[k]), sep = ", ";
    o << "},\n";
    const PlantedSignal& g = truth.signal;
    if (!g.known)
      o << "  \"signal\": null\n}\n";
    else
      o << fmt::format("  \"signal\": {{\"chi2\": {}, \"points\": {}, \"critical\": {}, \"oracle_power\": {}}}\n}}\n",
                       g.chi2, g.points, g.critical, g.oracle_power);
  });
  return truth;
}

}  // namespace gapflow
