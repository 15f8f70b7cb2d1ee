#include "calibrate/effect_responses.hpp"

#include "calibrate/effect_catalogue.hpp"
#include "common/geometry.hpp"
#include "common/statistics.hpp"
#include "common/toml_strict.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace gapflow {

namespace {

// Paired replicate differences (moved - reference) at point i over the reference's nodes, divided
// by `per`, in one order (node by node, replicate by replicate; NaN where either run is missing):
// moved[first + n] is node n moved.
std::vector<double> aligned_differences(const std::vector<Prediction>& moved, std::size_t first, const Reference& at,
                                        std::size_t i, double per) {
  std::vector<double> d;
  for (std::size_t n = 0; n < at.nodes.size(); ++n) {
    const Prediction& m = moved[first + n];
    const Prediction& b = at.predictions[n];
    for (std::size_t r = 0; r < b.replicate_fit[i].size(); ++r)
      d.push_back((m.replicate_fit[i][r] - b.replicate_fit[i][r]) / per);
  }
  return d;
}

std::vector<double> without_missing(std::vector<double> d) {
  d.erase(std::remove_if(d.begin(), d.end(), [](double x) { return std::isnan(x); }), d.end());
  return d;
}

// The same, only the pairs with both runs.
std::vector<double> paired_differences(const std::vector<Prediction>& moved, std::size_t first, const Reference& at,
                                       std::size_t i, double per) {
  return without_missing(aligned_differences(moved, first, at, i, per));
}

// Per point, the reference's runs in the pairs' order (aligned_differences): the partners of every
// size's moved runs (EffectTerm::partners).
std::vector<std::vector<double>> partner_runs(const Reference& at, std::size_t points) {
  std::vector<std::vector<double>> out(points);
  for (std::size_t i = 0; i < points; ++i)
    for (std::size_t n = 0; n < at.nodes.size(); ++n)
      for (double v : at.predictions[n].replicate_fit[i]) out[i].push_back(v);
  return out;
}

// Per data point, its observable's index in the order they first appear: the groups a term's sizes'
// correlation is pooled over (as the nodes' is, node_correlation.hpp).
std::vector<std::size_t> observable_groups(const DataFile& data) {
  std::vector<ObservableKind> seen;
  std::vector<std::size_t> out;
  for (const DataPoint& p : data.points) {
    const auto k = static_cast<std::size_t>(std::find(seen.begin(), seen.end(), p.observable) - seen.begin());
    if (k == seen.size()) seen.push_back(p.observable);
    out.push_back(k);
  }
  return out;
}

// A group's partner share (SizeCorrelation::partner_share), its mean over the sizes, as log text.
std::string partner_share_text(const EffectTerm& t, const SizeCorrelation& c) {
  if (c.partner_share.empty()) return "partner share -1/2 (not read)";
  double sum = 0;
  int n = 0;
  for (std::size_t j = 0; j < t.offsets.size(); ++j)
    if (t.offsets[j] != 0) sum += c.partner_share[j], ++n;
  return fmt::format("partner share {:+.2f}", sum / n);
}

// One log line: per observable, the mean correlation of the errors of neighbouring sizes' shifts
// (neutral's excluded: its shift is exact) and the partner share, or that the bound is used.
std::string size_correlation_text(const EffectTerm& t, const DataFile& data) {
  if (t.size_correlation.empty())
    return fmt::format("  {}: its sizes' errors' correlation is not known (not every size paired alike): its "
                       "variance is the bound over correlations in [0, 1]", t.effect);
  std::vector<std::string> parts;
  for (std::size_t g = 0; g < t.size_correlation.size(); ++g) {
    const auto first =
        static_cast<std::size_t>(std::find(t.pooled_in.begin(), t.pooled_in.end(), g) - t.pooled_in.begin());
    const std::string name = first < data.points.size() ? to_string(data.points[first].observable) : "all";
    const double c = t.neighbour_correlation(g);
    const SizeCorrelation& sc = t.size_correlation[g];
    const std::string correlation =
        sc.matrix.size() == 0 ? fmt::format("not counted ({} point(s) pooled, fewer than {}: the bound)", sc.points,
                                            SizeCorrelation::kMinPoints)
        : std::isnan(c)       ? std::string("n/a (one size)")
                              : fmt::format("{:+.2f} ({} points)", c, sc.points);
    parts.push_back(fmt::format("{} {}; {}", name, correlation, partner_share_text(t, sc)));
  }
  return fmt::format("  {}: its sizes' errors correlate between neighbouring sizes, counted in its variance: {}",
                     t.effect, fmt::join(parts, ", "));
}

// The nodes a term measured at `at` pairs its moved runs with: the reference's, when its runs
// are on the data file's seeds (those the surface's quadratic is made of where the nodes are
// baseline grid nodes); none on seeds of their own.
std::vector<ParameterSet> paired_nodes(const Reference& at) { return at.seed ? std::vector<ParameterSet>{} : at.nodes; }

// A step that stays inside [lo, hi] from `at` (reversed if needed).
double step_inside(double at, double step, double lo, double hi) {
  if (at + step <= hi + 1e-12 && at + step >= lo - 1e-12) return step;
  return -step;
}

// A size measured for a signature that was not kept stays in the effect's term: those are
// runs already made, and the size fit uses every measured size.
void add_measured_size(EffectTerm& term, const EffectTerm& other, double other_step) {
  std::vector<double> shift, se;
  for (std::size_t i = 0; i < other.slope.size(); ++i) {
    shift.push_back(other.slope[i] * other_step);
    se.push_back(other.slope_se[i] * std::abs(other_step));
  }
  term.add_size(other_step, shift, se);
}

}  // namespace

std::vector<ParameterSet> nodes_with_effects(const std::vector<ParameterSet>& nodes, const ParameterSet& effects_at,
                                             const std::vector<EffectTerm>& effects) {
  std::vector<ParameterSet> out;
  for (ParameterSet n : nodes) {
    for (const EffectTerm& t : effects) n = n.with(t.key, effects_at.get(t.key, t.neutral));
    out.push_back(std::move(n));
  }
  return out;
}

std::vector<double> refinement_offsets(const Candidate& c, const EffectDef& e) {
  const double step = c.step, sign = step > 0 ? 1.0 : -1.0;
  std::vector<double> out{step / 2};
  const double end = (step > 0 ? e.hi : e.lo) - c.neutral;
  if (std::abs(end) > 2.5 * std::abs(step)) out.push_back((step + end) / 2);
  if (std::abs(end) > 1.25 * std::abs(step)) out.push_back(end);
  const double other = (step > 0 ? e.lo : e.hi) - c.neutral;
  if (std::abs(other) > 0.25 * std::abs(step)) out.push_back(-sign * std::min(std::abs(other), std::abs(step)));
  return out;
}

std::vector<double> sizes_to_measure(const std::vector<double>& measured, const std::vector<double>& wanted,
                                     double min_spacing) {
  std::vector<double> sizes(measured);
  std::sort(sizes.begin(), sizes.end());
  std::vector<double> out;
  auto clear_of_all = [&](double da) {
    for (double m : sizes)
      if (std::abs(da - m) < min_spacing) return false;
    for (double m : out)
      if (std::abs(da - m) < min_spacing) return false;
    return true;
  };
  auto measured_already = [&](double da) {
    return std::any_of(sizes.begin(), sizes.end(), [&](double m) { return std::abs(da - m) <= 1e-12 * (1 + std::abs(m)); });
  };
  for (double da : wanted) {
    if (measured_already(da)) continue;
    if (!clear_of_all(da)) {
      // The middle of the measured gap that holds da (none beyond the outermost sizes).
      const auto above = std::upper_bound(sizes.begin(), sizes.end(), da);
      if (above == sizes.begin() || above == sizes.end()) continue;
      da = (*(above - 1) + *above) / 2;
      if (!clear_of_all(da)) continue;
    }
    out.push_back(da);
  }
  std::sort(out.begin(), out.end());
  return out;
}

Reference EffectResponses::reference_with(const BaselineFit& base, const ParameterSet& fitted,
                                          const std::vector<EffectTerm>& effects) {
  Reference r;
  std::vector<ParameterSet> near;
  for (std::size_t k : nearest_nodes(base.grid, base.surface, fitted)) near.push_back(base.grid[k]);
  r.nodes = nodes_with_effects(near, fitted, effects);
  r.anchor = fitted;
  std::vector<std::string> at;
  for (const ParameterSet& n : near) at.push_back(n.label());
  for (const EffectTerm& t : effects) at.push_back(fmt::format("{} = {:.4g}", t.key, fitted.get(t.key, t.neutral)));
  say_(fmt::format("reference: the {} grid node(s) nearest the fit, {} ({} runs, reused where made)", r.nodes.size(),
                   fmt::join(at, "; "),
                   batch_runs(r.nodes.size())));
  r.predictions = ev_.evaluate(r.nodes);
  return r;
}

std::size_t EffectResponses::batch_runs(std::size_t parameter_sets) const {
  return parameter_sets * data_.distinct_runs_per_replicate() * static_cast<std::size_t>(data_.model_replicates);
}

std::vector<Prediction> EffectResponses::evaluate_at(const Reference& at, const std::vector<ParameterSet>& sets) {
  return at.seed ? ev_.evaluate(sets, *at.seed, data_.model_replicates) : ev_.evaluate(sets);
}

Reference EffectResponses::on_own_seeds(const Reference& at, std::uint64_t seed) {
  Reference r = at;
  r.seed = seed;
  say_(fmt::format("signatures on seeds of their own (base seed {}): the {} reference node(s) run again ({} runs)", seed,
                   r.nodes.size(),
                   batch_runs(r.nodes.size())));
  r.predictions = evaluate_at(r, r.nodes);
  return r;
}

std::vector<Candidate> EffectResponses::signatures(const Reference& at, std::vector<EffectTerm>& terms) {
  std::vector<Candidate> cands;
  for (const EffectDef& e : effect_catalogue()) {
    if (!effect_applies(e, def_.model, data_)) continue;
    Candidate c;
    c.effect = e.name;
    c.key = e.key;
    c.neutral = neutral_value(e, data_);
    c.step = step_inside(c.neutral, e.step, e.lo, e.hi);
    cands.push_back(c);
  }
  std::vector<std::size_t> all(cands.size());
  for (std::size_t c = 0; c < cands.size(); ++c) all[c] = c;
  terms.assign(cands.size(), EffectTerm{});
  measure_signatures(cands, all, at, terms, "moved by their physical steps");
  // A signature lost in the noise points the score test nowhere (the data's residual is
  // projected on a direction that is mostly noise): measure it again at its range's end and
  // keep the step that moved the model more clearly (responses are not monotonic: a step
  // twice as large can move it less), with both sizes in the effect's term.
  std::vector<std::size_t> weak;
  std::vector<Candidate> first;
  std::vector<EffectTerm> first_terms;
  for (std::size_t c = 0; c < cands.size(); ++c) {
    const double far = valid_far_step(cands[c]);
    if (cands[c].signature_chi2 < def_.weak_signature_chi2_per_point * cands[c].signature_dof && far != 0) {
      weak.push_back(c);
      first.push_back(cands[c]);
      first_terms.push_back(terms[c]);
      cands[c].step = far;
    }
  }
  if (weak.empty()) return cands;
  measure_signatures(cands, weak, at, terms, "weak at their steps, measured at their ranges' ends");
  for (std::size_t k = 0; k < weak.size(); ++k) {
    Candidate& at_far = cands[weak[k]];
    EffectTerm& far_term = terms[weak[k]];
    // Clearer: the smaller visibility p (the two may count different points where one step
    // leaves some undefined); where both underflow, the larger chi^2 per point.
    const bool far_clearer =
        at_far.visibility_p < first[k].visibility_p ||
        (at_far.visibility_p == first[k].visibility_p &&
         at_far.signature_chi2 / std::max(1, at_far.signature_dof) > first[k].signature_chi2 / std::max(1, first[k].signature_dof));
    Candidate kept = far_clearer ? at_far : first[k];
    const Candidate& other = far_clearer ? first[k] : at_far;
    EffectTerm term = far_clearer ? far_term : first_terms[k];
    add_measured_size(term, far_clearer ? first_terms[k] : far_term, other.step);
    kept.other_step = other.step;
    kept.other_visibility_p = other.visibility_p;
    kept.other_signature_chi2 = other.signature_chi2;
    // The better of two looks: visible only at half the level (Bonferroni over the two), so
    // that a weak effect's chance of passing for visible stays at visible_p.
    kept.visible = kept.visibility_p < def_.visible_p / 2;
    at_far = std::move(kept);
    far_term = std::move(term);
  }
  return cands;
}

// The range's end on the step's side, moved toward neutral until every point still makes
// a scenario there (a corner radius cannot exceed an obstruction's inradius); 0 when that
// leaves less than 1.5 steps: there is no larger step to take.
double EffectResponses::valid_far_step(const Candidate& c) const {
  const EffectDef& e = *find_effect(c.effect);
  const std::optional<double> far = valid_offset(c.key, c.neutral, (c.step > 0 ? e.hi : e.lo) - c.neutral);
  return far && std::abs(*far) >= 1.5 * std::abs(c.step) ? *far : 0.0;
}

// `offset` from `neutral`, shrunk toward it (x 0.8 a try, at most 20) until every point
// makes a scenario with key = neutral + offset; none if it never does.
std::optional<double> EffectResponses::valid_offset(const std::string& key, double neutral, double offset) const {
  for (int k = 0; k <= 20; ++k, offset *= 0.8)
    if (valid_everywhere(key, neutral + offset)) return offset;
  return std::nullopt;
}

// Move the candidates `which` by their steps at every reference node (same seeds) and
// set their signatures, visibility and terms from the paired differences.
void EffectResponses::measure_signatures(std::vector<Candidate>& cands, const std::vector<std::size_t>& which,
                                         const Reference& at, std::vector<EffectTerm>& terms, const std::string& why) {
  std::vector<ParameterSet> sets;
  for (std::size_t c : which)
    for (const ParameterSet& n : at.nodes) sets.push_back(n.with(cands[c].key, cands[c].neutral + cands[c].step));
  say_(fmt::format("signatures: {} effect(s) {} at {} node(s) ({} runs)", which.size(), why, at.nodes.size(),
                   batch_runs(sets.size())));
  const std::vector<Prediction> moved = evaluate_at(at, sets);
  for (std::size_t k = 0; k < which.size(); ++k) {
    Candidate& cand = cands[which[k]];
    const EffectDef& e = *find_effect(cand.effect);
    std::vector<double> slope, slope_se;
    std::vector<std::vector<double>> diffs;
    for (std::size_t i = 0; i < data_.points.size(); ++i) {
      diffs.push_back(paired_differences(moved, k * at.nodes.size(), at, i, cand.step));
      const Summary s = summarize(diffs.back());
      slope.push_back(diffs.back().size() >= 2 ? s.mean : 0.0);
      slope_se.push_back(diffs.back().size() >= 2 ? s.se() : 0.0);
    }
    // Pass 5 of the blind study lost both corner-rounding twins here: the 28 fitted points
    // without an obstruction (identical runs) counted as degrees of freedom beside the 4 with it.
    const Visibility v = step_visibility(diffs, data_.held_out_flags());
    EffectTerm t = EffectTerm::single_step(e.name, e.key, cand.neutral, e.lo, e.hi, cand.step, slope, slope_se);
    t.paired_with = paired_nodes(at);
    cand.signature = t.slope;
    cand.signature_chi2 = v.chi2;
    cand.signature_dof = v.dof;
    cand.visibility_p = v.p;
    cand.visible = cand.visibility_p < def_.visible_p;
    terms[which[k]] = std::move(t);
  }
}

void EffectResponses::refine(EffectTerm& term, const Candidate& c, const Reference& at) {
  add_sizes(term, c, refinement_offsets(c, *find_effect(c.effect)), at);
}

EffectTerm EffectResponses::measure_term(const Candidate& c, const Reference& at) {
  const EffectDef& e = *find_effect(c.effect);
  EffectTerm term;
  term.effect = e.name;
  term.key = e.key;
  term.neutral = c.neutral;
  term.lo = e.lo;
  term.hi = e.hi;
  term.offsets = {0.0};
  term.shift = {std::vector<double>(data_.points.size(), 0.0)};
  term.shift_se = term.shift;
  term.paired_with = paired_nodes(at);
  std::vector<double> offsets{c.step};
  for (double da : refinement_offsets(c, e)) offsets.push_back(da);
  add_sizes(term, c, offsets, at);
  // The slope at the step, as a one-size term would have it (reported; the fit reads the sizes).
  const auto s = std::find(term.offsets.begin(), term.offsets.end(), c.step);
  if (s != term.offsets.end()) {
    const std::size_t k = static_cast<std::size_t>(s - term.offsets.begin());
    for (std::size_t i = 0; i < data_.points.size(); ++i) {
      term.slope.push_back(term.shift[k][i] / c.step);
      term.slope_se.push_back(term.shift_se[k][i] / std::abs(c.step));
    }
  } else {
    term.slope = c.signature;
    term.slope_se.assign(data_.points.size(), 0.0);
  }
  return term;
}

// Measure an effect at more sizes (offsets from neutral) at the reference's nodes, so that
// its size is fitted on its measured response, not on a line through one step.
void EffectResponses::add_sizes(EffectTerm& term, const Candidate& c, const std::vector<double>& wanted,
                                const Reference& at) {
  // Every size of a term pairs with the same runs (EffectTerm::paired_with).
  const auto same_nodes = [](const std::vector<ParameterSet>& a, const std::vector<ParameterSet>& b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                      [](const ParameterSet& x, const ParameterSet& y) { return x.values == y.values; });
  };
  if (!same_nodes(term.paired_with, paired_nodes(at)))
    throw std::logic_error(fmt::format("{}: more sizes measured against other runs than its first ones", c.effect));
  // Sizes that make no scenario go first, so that they move or drop no other size.
  std::vector<double> valid, offsets;
  for (double da : wanted)
    if (valid_everywhere(c.key, c.neutral + da)) valid.push_back(da);
  for (double da : sizes_to_measure(term.offsets, valid, std::abs(c.step) / 4))
    if (valid_everywhere(c.key, c.neutral + da)) offsets.push_back(da);
  // The fit may move the size only where every point still makes a scenario (a gap offset
  // below -W closes the gap): the range shrinks toward neutral until it does.
  for (double* bound : {&term.lo, &term.hi})
    *bound = c.neutral + valid_offset(c.key, c.neutral, *bound - c.neutral).value_or(0.0);
  if (offsets.empty()) {
    say_(fmt::format("{}: no more size to measure (each wanted one makes no scenario, is measured already or lies "
                     "within a quarter step of one)",
                     c.effect));
    return;
  }
  std::vector<ParameterSet> sets;
  for (double da : offsets)
    for (const ParameterSet& n : at.nodes) sets.push_back(n.with(c.key, c.neutral + da));
  say_(fmt::format("{}: response measured at {} {}size(s) ({}) at {} node(s)", c.effect, offsets.size(),
                   term.offsets.size() > 1 ? "more " : "", fmt::join(offsets, ", "), at.nodes.size()));
  const std::vector<Prediction> moved = evaluate_at(at, sets);
  term.pooled_in = observable_groups(data_);
  if (!paired_nodes(at).empty()) term.partners = partner_runs(at, data_.points.size());
  for (std::size_t k = 0; k < offsets.size(); ++k) {
    std::vector<double> shift, se;
    std::vector<std::vector<double>> pairs;
    for (std::size_t i = 0; i < data_.points.size(); ++i) {
      pairs.push_back(aligned_differences(moved, k * at.nodes.size(), at, i, 1.0));
      const Summary s = summarize(without_missing(pairs.back()));
      shift.push_back(s.n >= 2 ? s.mean : 0.0);
      se.push_back(s.n >= 2 ? s.se() : 0.0);
    }
    term.add_size(offsets[k], shift, se, std::move(pairs));
  }
  say_(size_correlation_text(term, data_));
}

// Whether every point makes a valid scenario with `key` = value (where the key applies).
bool EffectResponses::valid_everywhere(const std::string& key, double value) const {
  for (std::size_t i = 0; i < data_.points.size(); ++i) {
    if (!key_applies_to(key, data_.point_scenario(i).def)) continue;
    try {
      (void)compile_scenario(data_.point_scenario(i, {key + "=" + number_text(value)}).def);
    } catch (const ScenarioError&) {
      return false;
    } catch (const ScenarioInvalid&) {
      return false;
    }
  }
  return true;
}

}  // namespace gapflow
