#include "calibrate/calibration_report.hpp"

#include "calibrate/detectability.hpp"
#include "calibrate/effect_catalogue.hpp"
#include "calibrate/fit.hpp"
#include "common/json_text.hpp"
#include "common/text_file.hpp"
#include "studies/report.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <iostream>
#include <ostream>

#ifndef GAPFLOW_CALIBRATION_PLOT_SCRIPT
#define GAPFLOW_CALIBRATION_PLOT_SCRIPT "calibrate/plot_calibration.py"
#endif

namespace gapflow {

namespace {

std::string json_errors(const ErrorMeasures& e) {
  return fmt::format(R"({{"n": {}, "rmse": {}, "rms_whitened": {}, "chi2": {}, "dof": {}, "p": {}, "invalid": {}}})", e.n,
                     json_number(e.rmse), json_number(e.rms_whitened), json_number(e.chi.chi2), e.chi.dof,
                     json_number(e.chi.p), e.invalid);
}

std::string json_params(const ParameterSet& p) {
  std::string s;
  for (const auto& [k, v] : p.values) s += fmt::format("{}{}: {}", s.empty() ? "" : ", ", json_string(k), json_number(v));
  return "{" + s + "}";
}

// {"key": [lo, hi], ...}: the surface window's range of each free parameter.
std::string json_window(const ModelState& s) {
  std::string out;
  for (std::size_t k = 0; k < s.window_keys.size(); ++k)
    out += fmt::format("{}{}: [{}, {}]", out.empty() ? "" : ", ", json_string(s.window_keys[k]), json_number(s.window_lo[k]),
                       json_number(s.window_hi[k]));
  return "{" + out + "}";
}

std::string json_state(const ModelState& s) {
  return fmt::format(R"({{"params": {}, "fitted": {}, "held_out": {}, "fitted_fresh": {}, "held_out_fresh": {}, "bic": {}, )"
                     R"("surface_window": {}}})",
                     json_params(s.params), json_errors(s.fitted), json_errors(s.held_out), json_errors(s.fitted_fresh),
                     json_errors(s.held_out_fresh), json_number(s.bic), json_window(s));
}

std::string json_list(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + json_string(x);
  return "[" + s + "]";
}

// The baseline round's candidates at the loop's level, 80 % power (detectability.hpp). Empty when
// no candidate was measured (--max-effects 0).
std::vector<Detectability> baseline_detectability(const CalibrationResult& r) {
  if (r.rounds.empty()) return {};
  return detectability_at_baseline(r.rounds.front(), r.before.fitted.chi.dof, {.alpha = r.alpha, .power = 0.8});
}

void write_detectability_md(std::ostream& o, const CalibrationResult& r) {
  const std::vector<Detectability> seen = baseline_detectability(r);
  if (seen.empty()) return;
  o << fmt::format(
      "\n## The smallest effect these data could see, at best\n\nFor each effect, the smallest departure from its "
      "neutral value at which each of the two tests the loop puts before any attribution has 80 % power: the fitted "
      "points' chi2 at level {0} and the effect's score at level {0} / (visible candidates). Linear at the baseline "
      "fit, the effect added on top of the fitted parameters with their directions projected out. A lower bound: a "
      "smaller departure passes these tests less often (about half the time at 0.8 times the bound); a larger one "
      "can still be missed, because the effect must then lower BIC, keep the held-out points and win against its "
      "rivals, and because an effect that interacts with the fitted parameters can be absorbed by a large move of "
      "them, which this linear view cannot see (calibrate/README.md, step 7: in a blind twin a rolling resistance "
      "at twice its bound went unseen). A verdict 'consistent with noise' therefore does not exclude departures "
      "above these sizes either.\n\n| effect | neutral | smallest detectable departure, at best |\n|---|---|---|\n",
      r.alpha);
  for (const Detectability& d : seen)
    o << fmt::format("| {} | {:g} | {} |\n", d.effect, d.neutral, detectability_text(d));
}

std::string spread_text(double spread) {
  if (std::isnan(spread)) return "no order";
  if (std::isinf(spread)) return "none";
  return fmt::format("{:.0f} %", 100 * spread);
}

// Whether each added effect is one size across the design (form_check.hpp).
void write_form_checks_md(std::ostream& o, const CalibrationResult& r) {
  if (r.form_checks.empty()) return;
  o << "\n## Is each added effect one size across the design?\n\nA catalogue effect is one constant of the setup "
       "at every design point. Here its sensitivity is split by each design column's levels (and by observable; a level "
       "needs two fitted points the effect moves), and a score test asks whether the residual after the fit wants "
       "different sizes at different levels (dof: levels - 1). Its p is Fisher's F on (dof, rest dof) against the "
       "residual outside the fitted and tested directions (*scale*: that residual's chi2 / rest dof; exact for any "
       "common scale of the noise), adjusted by Bonferroni over the checks below. A significant one says the effect's one size does not fit the "
       "design, as an effect of another form read as this one would (a drag quadratic in the speed read as a linear "
       "drag asks for more drag where the spheres run faster); it names no other effect. Linear, at the fit: it sees a "
       "mismatch only along what the design varies. *Detectable spread*: what the check could see, the smallest "
       "difference of the effect's departure from neutral between the column's lowest and highest level, as a share of "
       "the fitted departure, that it flags with power 0.8 at the stated noise (a trend straight in the level's value; "
       "100 %: the ends differ by the fitted departure; where the scale is below 1 the noise is smaller than stated and "
       "the spread smaller by sqrt(scale)). A drag k v^2 read as a linear drag needs about the spheres' "
       "relative speed difference across the column. *Another law*: for a drag, along the incline, the spread a drag "
       "quadratic in the speed read as this linear one asks (sizes as sqrt(sin theta): speeds from rest on the board, "
       "to first order) and the check's power against it at the stated noise; below 0.8 the design does not determine "
       "the drag's law, and the verdict says so (its own section below).\n\n| effect | split by | levels | statistic | dof | rest dof | "
       "scale | p | adjusted p | detectable spread | another law: spread, power |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const FormCheck& c : r.form_checks)
    o << fmt::format("| {} | {} | {} | {:.2f} | {} | {} | {:.2f} | {:.3g} | {:.3g} | {} | {} |\n", c.effect, c.column,
                     c.levels, c.statistic, c.dof, c.rest_dof, c.scale, c.p, c.p_adjusted, spread_text(c.detectable_spread),
                     std::isfinite(c.law_power) ? fmt::format("{:.0f} %, {:.2f}", 100 * c.law_spread, c.law_power) : "-");
  // Out of the verdict since passes 21-22 (decisions.hpp, rule 3): 5 false alarms in 31.
  o << (r.form_differs ? "\nAt least one differs (adjusted p < alpha). The verdict does not say so: on the blind "
                         "study's design this check flagged 5 of 31 correctly identified effects (passes 21 and 22), "
                         "above its 5 % level, so a flag is a lead to look into, not a finding.\n"
                       : "\nNone differs at the loop's level.\n");
}

// Whether the design determines an added drag's law in the speed (form_check.hpp): its own
// section, since a drag no check could ask about has no form-check section to sit in.
void write_law_md(std::ostream& o, const CalibrationResult& r) {
  if (!std::isfinite(r.law_power)) return;
  const std::string power = fmt::format("power {:.2f} against a drag quadratic in the speed", r.law_power);
  o << "\n## The added drag's law in the speed\n\n"
    << (!r.law_undetermined
            ? "Established as linear: the check along the incline had " + power + " and did not flag it.\n"
        : r.law_power < FormCheckDef{}.power  // the loop's (calibration.cpp: the form checks' default)
            ? "Not established: this design cannot tell it (" + power + "; 0: no check along the incline could be "
              "made). A drag of another law may be acting, and the size is that of the linear drag that mimics it here.\n"
            : "Not established: the check along the incline, with " + power + ", flags the drag's size as changing "
              "across the inclines, as a drag of another law's would (a lead, not a finding: the form check's flags "
              "are out of the verdict).\n");
}

void write_summary_json(std::ostream& o, const DataFile& data, const CalibrationResult& r) {
  o << "{\n";
  // "observable": the points' default kind (a name, as before several observables per file);
  // "observables": every kind with its scale and point count, for people.
  o << fmt::format("  \"data\": {},\n  \"data_file\": {},\n  \"model\": {},\n  \"observable\": {},\n  \"observables\": {},\n",
                   json_string(r.data_name), json_string(data.file.string()), json_string(r.model),
                   json_string(to_string(data.observable)), json_string(data.observables_text()));
  std::string measured;
  for (const FreeParameter& f : data.free)
    if (f.has_measurement())
      measured += fmt::format("{}{{\"key\": {}, \"measured\": {}, \"se\": {}}}", measured.empty() ? "" : ", ",
                              json_string(f.key), json_number(f.measured), json_number(f.measured_se));
  o << "  \"measured_free\": [" << measured << "],\n";
  o << fmt::format("  \"model_replicates\": {},\n  \"model_noise_share\": {},\n  \"surface_noise_ratio\": {},\n"
                   "  \"node_correlation\": {},\n  \"surface_noise_counted\": {},\n",
                   data.model_replicates, json_number(r.model_noise_share), json_number(r.surface_noise_ratio),
                   json_number(r.node_correlation), json_number(r.surface_noise_counted));
  o << fmt::format("  \"shared_covariance_at_bound\": {},\n  \"shared_covariance_pairs\": {},\n",
                   r.shared_covariance_bound.at_bound, r.shared_covariance_bound.pairs);
  o << fmt::format("  \"contenders\": {},\n", r.contenders);
  o << fmt::format("  \"alternatives\": {},\n", r.alternatives);
  o << fmt::format("  \"decisive_score_p\": {},\n", r.decisive_score_p);
  o << fmt::format("  \"held_out_route\": {},\n", r.held_out_route ? "true" : "false");
  o << fmt::format("  \"independent_signatures\": {},\n", r.independent_signatures ? "true" : "false");
  o << fmt::format("  \"verdict\": {},\n  \"poor_fit\": {},\n  \"held_out_beyond_noise\": {},\n", json_string(r.verdict),
                   r.poor_fit ? "true" : "false", r.held_out_beyond_noise ? "true" : "false");
  o << fmt::format("  \"held_out_fresh_fit_aware\": {{\"chi2\": {}, \"dof\": {}, \"p\": {}}},\n",
                   json_number(r.held_out_fresh_fit_aware.chi2), r.held_out_fresh_fit_aware.dof,
                   json_number(r.held_out_fresh_fit_aware.p));
  o << "  \"effects\": [";
  for (std::size_t i = 0; i < r.effects.size(); ++i) {
    const AddedEffect& e = r.effects[i];
    o << fmt::format(R"({}{{"effect": {}, "key": {}, "group": {}, "alternatives": {}, "neutral": {}, "value": {}, "lo95": {}, "hi95": {}, "interval_bounded": {}, "size_correlation": {}}})",
                     i ? ", " : "", json_string(e.effect), json_string(e.key), json_list(e.group),
                     json_list(e.alternatives), json_number(e.neutral),
                     json_number(e.value), json_number(e.lo95), json_number(e.hi95), e.interval_bounded ? "true" : "false",
                     json_number(e.size_correlation));
  }
  o << "],\n";
  o << fmt::format("  \"law_power\": {},\n  \"law_undetermined\": {},\n", json_number(r.law_power),
                   r.law_undetermined ? "true" : "false");
  o << fmt::format("  \"form_differs\": {},\n  \"form_checks\": [", r.form_differs ? "true" : "false");
  for (std::size_t i = 0; i < r.form_checks.size(); ++i) {
    const FormCheck& c = r.form_checks[i];
    o << fmt::format(R"({}{{"effect": {}, "column": {}, "levels": {}, "statistic": {}, "dof": {}, "rest_dof": {}, "scale": {}, "p": {}, "p_adjusted": {}, "trend_ordered": {}, "spread_level": {}, "detectable_spread": {}, "law_spread": {}, "law_power": {}}})",
                     i ? ", " : "", json_string(c.effect), json_string(c.column), c.levels, json_number(c.statistic),
                     c.dof, c.rest_dof, json_number(c.scale), json_number(c.p), json_number(c.p_adjusted),
                     std::isnan(c.trend_noncentrality) ? "false" : "true", json_number(c.spread_level),
                     json_number(c.detectable_spread), json_number(c.law_spread), json_number(c.law_power));
  }
  o << "],\n";
  o << "  \"before\": " << json_state(r.before) << ",\n";
  o << "  \"after\": " << json_state(r.after) << ",\n";
  o << "  \"rounds\": [";
  for (std::size_t i = 0; i < r.rounds.size(); ++i) {
    const Round& rd = r.rounds[i];
    std::string groups;
    for (const auto& g : rd.groups) groups += (groups.empty() ? "" : ", ") + json_list(g);
    std::string fits;
    for (const ContenderFit& f : rd.fits)
      fits += fmt::format(R"({}{{"effect": {}, "value": {}, "bic": {}, "at_neutral": {}, "fitted_chi2": {}, "fitted_dof": {}, "fitted_p": {}}})",
                          fits.empty() ? "" : ", ", json_string(f.effect), json_number(f.value), json_number(f.bic),
                          f.at_neutral ? "true" : "false", json_number(f.fitted.chi2), f.fitted.dof,
                          json_number(f.fitted.p));
    o << fmt::format("{}\n    {{\"best\": {}, \"decision\": {}, \"groups\": [{}], \"rivals\": {}, \"fits\": [{}], "
                     "\"alternatives\": {}, \"candidates\": [",
                     i ? "," : "", json_string(rd.best), json_string(rd.decision), groups, json_list(rd.rivals), fits,
                     json_list(rd.alternatives));
    for (std::size_t c = 0; c < rd.candidates.size(); ++c) {
      const Candidate& k = rd.candidates[c];
      o << fmt::format(R"({}{{"effect": {}, "step": {}, "other_step": {}, "other_visibility_p": {}, "visible": {}, "visibility_p": {}, "signature_chi2": {}, "signature_points": {}, "score": {}, "p": {}, "p_adjusted": {}, "estimate": {}, "left_by_fit": {}, "direction_possible": {}, "group": {}}})",
                       c ? ", " : "", json_string(k.effect), json_number(k.step),
                       k.other_step != 0 ? json_number(k.other_step) : "null",
                       k.other_step != 0 ? json_number(k.other_visibility_p) : "null", k.visible ? "true" : "false",
                       json_number(k.visibility_p), json_number(k.signature_chi2), k.signature_dof, json_number(k.score.statistic), json_number(k.score.p),
                       json_number(k.p_adjusted), json_number(k.score.estimate),
                       k.visible ? json_number(k.score.left_by_fit()) : "null",
                       k.direction_possible ? "true" : "false", k.group);
    }
    o << "]}";
  }
  o << "\n  ],\n";
  o << "  \"detectability\": [";
  const std::vector<Detectability> seen = baseline_detectability(r);
  for (std::size_t i = 0; i < seen.size(); ++i) {
    const Detectability& d = seen[i];
    const bool bounded = d.visible && !d.absorbed && std::isfinite(d.min_departure);  // else null: none detectable
    o << fmt::format(R"({}{{"effect": {}, "neutral": {}, "lo": {}, "hi": {}, "visible": {}, "absorbed": {}, "min_departure": {}, "within_range": {}, "largest_step": {}, "largest_step_p": {}, "step_reached_range_end": {}}})",
                     i ? ", " : "", json_string(d.effect), json_number(d.neutral), json_number(d.lo), json_number(d.hi),
                     d.visible ? "true" : "false", d.absorbed ? "true" : "false",
                     bounded ? json_number(d.min_departure) : "null",
                     bounded ? (d.within_range ? "true" : "false") : "null", json_number(d.largest_step),
                     json_number(d.largest_step_p), d.step_reached_range_end ? "true" : "false");
  }
  o << "],\n";
  o << fmt::format("  \"runs_simulated\": {},\n  \"runs_reused\": {},\n  \"run_seconds\": {},\n  \"cpu_seconds\": {},\n"
                   "  \"wall_seconds\": {}\n}}\n",
                   r.runs_simulated, r.runs_reused, json_number(r.run_seconds), json_number(r.cpu_seconds),
                   json_number(r.wall_seconds));
}

void write_points_csv(std::ostream& o, const DataFile& data, const CalibrationResult& r) {
  for (const DesignColumn& c : data.design) o << c.column << ",";
  // The surface's predictions (before, after) and, appended, the direct simulation's on fresh seeds at
  // the same parameters (before_fresh, after_fresh): their difference per point is the surface's error there.
  o << "observable,held_out,value,se,before,before_se,after,after_se,residual_before,residual_after,"
       "before_fresh,before_fresh_se,after_fresh,after_fresh_se\n";
  const Prediction& b = r.before.prediction;
  const Prediction& a = r.after.prediction;
  const Prediction& bf = r.before.simulated_fresh;
  const Prediction& af = r.after.simulated_fresh;
  // Empty where the model gave no value (or, for a fresh prediction, where none was made).
  auto model_value = [&](const Prediction& p, std::size_t i) {
    return i < p.valid.size() && p.valid[i] ? fmt::format("{}", p.value[i]) : "";
  };
  auto model_se = [&](const Prediction& p, std::size_t i) {
    // Back to the observable's unit (log scale: se_fit is relative).
    if (i >= p.valid.size() || !p.valid[i]) return std::string();
    return fmt::format("{}", data.points[i].scale == FitScale::log ? p.se_fit[i] * p.value[i] : p.se_fit[i]);
  };
  for (std::size_t i = 0; i < data.points.size(); ++i) {
    for (const std::string& v : data.points[i].design) o << (v.front() == '"' ? v.substr(1, v.size() - 2) : v) << ",";
    o << fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", to_string(data.points[i].observable),
                     data.points[i].held_out ? 1 : 0, data.points[i].value,
                     data.points[i].se, model_value(b, i), model_se(b, i), model_value(a, i), model_se(a, i),
                     r.before.whitened[i], r.after.whitened[i], model_value(bf, i), model_se(bf, i), model_value(af, i),
                     model_se(af, i));
  }
}

// The step column: one step, or the two measured (the kept one last, or the tried one in brackets).
std::string step_text(const Candidate& c) {
  if (c.other_step == 0) return fmt::format("{:.3g}", c.step);
  if (std::abs(c.step) > std::abs(c.other_step)) return fmt::format("{:.3g} -> {:.3g}", c.other_step, c.step);
  return fmt::format("{:.3g} ({:.3g} tried)", c.step, c.other_step);
}

std::string visibility_text(const Candidate& c) {
  if (c.other_step == 0) return fmt::format("{:.2g}", c.visibility_p);
  if (std::abs(c.step) > std::abs(c.other_step)) return fmt::format("{:.2g} -> {:.2g}", c.other_visibility_p, c.visibility_p);
  return fmt::format("{:.2g}; {:.2g} at {:.3g}", c.visibility_p, c.other_visibility_p, c.other_step);
}

std::string errors_row(const char* what, const ErrorMeasures& e) {
  if (e.n == 0) return fmt::format("| {} | 0 | | | | |\n", what);
  return fmt::format("| {} | {} | {:.4f} | {:.2f} | {:.2f} / {} = {:.2f} | {:.3g} |\n", what, e.n, e.rmse, e.rms_whitened,
                     e.chi.chi2, e.chi.dof, e.chi.per_dof(), e.chi.p);
}

void write_report_md(std::ostream& o, const DataFile& data, const CalibrationResult& r) {
  o << fmt::format("# Calibration: {} against the {} model\n\n", r.data_name, r.model);
  o << fmt::format("Data: `{}` ({} points, {} held out), observable {}. Source: {} ({}). {}\n\n",
                   data.file.string(), data.points.size(), data.points.size() - data.fitted_count(),
                   data.observables_text(), data.source.citation,
                   data.source.method, data.source.uncertainty);
  o << fmt::format("**Verdict: {}.**", r.verdict);
  for (const AddedEffect& e : r.effects) {
    const EffectDef* d = find_effect(e.effect);
    // An interval that is not bounded is still the profile's: it reached the end of the effect's
    // range (its plausible range, shrunk to where every point still makes a scenario).
    o << fmt::format(" Added `{}` = {:.4g} {} (95 % profile interval [{:.4g}, {:.4g}]{}; without it {:.4g}){}.", e.key,
                     e.value, d ? d->unit : "", e.lo95, e.hi95,
                     e.interval_bounded ? "" : ", cut at the end of the range the fit may move it in", e.neutral,
                     e.group.size() > 1 ? fmt::format(", standing for the group {{{}}} that this design cannot tell apart", fmt::join(e.group, ", ")) : "");
    if (!e.alternatives.empty())
      o << fmt::format(" These data do not exclude {} in its place: fitted instead of it (with whatever was added "
                       "before it), {} the fitted points within the noise (chi2 p >= {:.2g}; section \"Candidate "
                       "effects\").",
                       fmt::join(e.alternatives, ", "), e.alternatives.size() > 1 ? "each leaves" : "it leaves", r.alpha);
  }
  // An attribution is a choice among the catalogue's effects: one outside it that changes these
  // observables the same way can pass every test as the catalogue effect it resembles (blind pass
  // 20's quadratic drag, read as linear drag within the noise; README, Calibration, limits).
  if (!r.effects.empty()) {
    o << " Added effects are chosen from the effect catalogue (`calibrate/effect_catalogue.cpp`): an effect outside it "
         "that changes these observables the same way, within the noise, could be reported as the catalogue effect "
         "(or group) it most resembles.";
    if (r.poor_fit || r.held_out_beyond_noise) o << " Where the fit stays poor, what remains may be such an effect.";
    if (r.form_differs)
      o << " The form check finds an added effect's size differing across the design (section \"Is each added effect "
           "one size across the design?\"; not in the verdict, for its false alarms): such an effect may be acting in "
           "its place.";
    if (r.law_undetermined)
      o << " The added drag's law in the speed is not established (section \"The added drag's law in the speed\"): a "
           "drag of another law would be read as this one.";
  }
  if (r.poor_fit)
    o << (r.effects.empty() ? " The fit is poor (chi2 p < 0.01 on the fitted points)."
                            : " The fit is still poor after the additions (chi2 p < 0.01): read any attribution with care.");
  if (r.held_out_beyond_noise) {
    // Why they matter depends on what the fitted points said.
    const char* reading =
        !r.effects.empty() ? ": the model is likely still missing something where the design was not fitted"
        : r.verdict == "unexplained residual: the held-out points are beyond the noise"
            ? ": the model likely misses something that the fitted parameters take in where the data were fitted"
            : ": the model misses something at the fitted and the held-out points alike";
    o << fmt::format(" The held-out points, simulated on fresh seeds, are beyond the noise (chi2 p = {:.3g}, the fitted "
                     "parameters' uncertainty included){}.",
                     r.held_out_fresh_fit_aware.p, reading);
  }
  std::string measured;
  for (const FreeParameter& f : data.free)
    if (f.has_measurement()) measured += fmt::format("{}`{}` = {:.4g} +- {:.4g}", measured.empty() ? "" : ", ", f.key, f.measured, f.measured_se);
  o << "\n\n## Error before and after\n\nRMSE on the fit scale (log scale: about a relative error); RMS of the whitened residual (1 = at the noise floor); chi2/nu with its p-value (fitted points: nu = n - fitted parameters; held-out points: nu = n).";
  if (!measured.empty())
    o << " The data file gives independent measurements of free parameters (" << measured
      << "): each is one more fitted datum, in every fit and in the fitted points' chi2 and nu (not in n, RMSE or RMS).";
  o << "\n\n";
  o << "| points | n | RMSE | RMS/noise | chi2 / nu | p |\n|---|---|---|---|---|---|\n";
  o << errors_row("before, fitted", r.before.fitted) << errors_row("before, held out", r.before.held_out);
  o << errors_row("before, fitted, fresh seeds", r.before.fitted_fresh) << errors_row("before, held out, fresh seeds", r.before.held_out_fresh);
  o << errors_row("after, fitted", r.after.fitted) << errors_row("after, held out", r.after.held_out);
  o << errors_row("after, fitted, fresh seeds", r.after.fitted_fresh) << errors_row("after, held out, fresh seeds", r.after.held_out_fresh);
  if (r.held_out_fresh_fit_aware.dof > 0)
    o << fmt::format("| after, held out, fresh seeds, the fit's uncertainty included (the verdict's test) | {} | | | {:.2f} / {} = {:.2f} | {:.3g} |\n",
                     r.held_out_fresh_fit_aware.dof, r.held_out_fresh_fit_aware.chi2, r.held_out_fresh_fit_aware.dof,
                     r.held_out_fresh_fit_aware.per_dof(), r.held_out_fresh_fit_aware.p);
  o << fmt::format("\nParameters before: {}. After: {}. BIC {:.2f} -> {:.2f}.\n", r.before.params.label(), r.after.params.label(),
                   r.before.bic, r.after.bic);
  // Where a measured parameter ended, in its measurement's standard errors: a poor fit that comes
  // from pulling against the measurement reads differently from one the points alone show.
  for (const FreeParameter& f : data.free)
    if (f.has_measurement())
      o << fmt::format("`{}` against its measurement {:.4g} +- {:.4g}: {:+.2f} se before, {:+.2f} se after.\n", f.key,
                       f.measured, f.measured_se, (r.before.params.get(f.key, f.measured) - f.measured) / f.measured_se,
                       (r.after.params.get(f.key, f.measured) - f.measured) / f.measured_se);
  o << "\n## Candidate effects\n\nEach effect moved by its physical step at the baseline fit (same seeds); *visible* when that moved the model beyond its noise (paired chi2, p < 0.01). Score test of the signature, with the fitted parameters projected out, against the residual; p adjusted (Bonferroni) over the visible candidates. An effect whose range lies on one side of its neutral value (most: a drag, a tilt, a rounding cannot go below none) is scored one-sided: where its linearised size points outside the range, its score is 0 and p 1 (marked). A step whose paired chi2 stays below 4 per fitted point (2 se a point) leaves a signature mostly noise: the effect is moved again to the end of its range (or as far toward it as every point allows) and the step that moved the model more clearly is used (*step -> end*: the end; *step (end tried)*: the first), visible then at half the level (the better of two looks). *Left by the fit*: the share of the signature's length that the fitted parameters cannot mimic, |P u| / |u| (whitened): near 0, the effect is absorbed by the fit in this design, and whatever of it the data hold ends up in the fitted parameters; a design that varies what tells them apart is needed to see it.\n";
  for (std::size_t i = 0; i < r.rounds.size(); ++i) {
    const Round& rd = r.rounds[i];
    o << fmt::format("\n### Round {}\n\n| effect | step | visible (p) | left by the fit | score | p | adjusted p | linearised size | group |\n|---|---|---|---|---|---|---|---|---|\n", i + 1);
    for (const Candidate& c : rd.candidates)
      o << fmt::format("| {} | {} | {} ({}) | {} | {} | {} | {} | {} | {} |\n", c.effect,
                       step_text(c),
                       c.visible ? "yes" : "no",
                       visibility_text(c),
                       c.visible ? fmt::format("{:.0f} %", 100 * c.score.left_by_fit()) : "",
                       c.visible ? fmt::format("{:.2f}", c.score.statistic) : "",
                       c.visible ? fmt::format("{:.3g}", c.score.p) : "", c.visible ? fmt::format("{:.3g}", c.p_adjusted) : "",
                       c.visible ? fmt::format("{:.4g} ± {:.2g}{}", c.neutral + c.score.estimate, c.score.se,
                                               c.direction_possible ? "" : " (outside its range: score 0)")
                                 : "",
                       c.group >= 0 ? std::to_string(c.group) : "");
    for (const auto& g : rd.groups) o << fmt::format("\nIndistinguishable in this design (|cos| > 0.9): {}.\n", fmt::join(g, ", "));
    if (!rd.fits.empty()) {
      o << "\nSignificant candidates fitted in full, each on its measured response with the free parameters ("
        << (r.contenders >= 2
                ? "the score ranks them by a linear view at the round's start; among the first " +
                      std::to_string(r.contenders) + ", the lowest BIC is the one tried, a fit at its effect's neutral "
                      "value never"
                : "the best score is the one tried")
        << (r.alternatives > 0 ? "; any other whose fit, alone, leaves the fitted points within the noise (chi2 p >= "
                                 "alpha) is an alternative these data do not exclude in its place"
                               : "")
        << "):\n\n| effect | fitted size | BIC | fitted chi2 / nu (p) | at neutral |\n|---|---|---|---|---|\n";
      for (const ContenderFit& f : rd.fits)
        o << fmt::format("| {} | {:.4g} | {:.1f} | {:.2f} / {} ({:.3g}) | {} |\n", f.effect, f.value, f.bic,
                         f.fitted.chi2, f.fitted.dof, f.fitted.p, f.at_neutral ? "yes" : "");
      if (r.alternatives > 0)
        o << (rd.alternatives.empty()
                  ? std::string("\nNo other, in its place, leaves the fitted points within the noise.\n")
                  : fmt::format("\nIn place of {}, these leave the fitted points within the noise (chi2 p >= "
                                "alpha): {}.\n",
                                rd.best, fmt::join(rd.alternatives, ", ")));
    }
    if (rd.rivals.size() > 1)
      o << fmt::format(fmt::runtime(r.contenders < 2 || rd.fits.empty() ? "\nThese data cannot rank them below the best (score within chi2_1(0.95) = "
                                         "3.84 of {}): {}.\n"
                                       : "\nThese data cannot rank them below the one tried ({}; fitted BIC within "
                                         "chi2_1(0.95) = 3.84, or score within 3.84 and not fitted): {}.\n"),
                       rd.best, fmt::join(rd.rivals, ", "));
    o << fmt::format("\nDecision: {}.\n", rd.decision);
  }
  write_form_checks_md(o, r);
  write_law_md(o, r);
  write_detectability_md(o, r);
  o << "\n## Log\n\n```\n";
  for (const std::string& l : r.log) o << l << "\n";
  o << "```\n";
  o << fmt::format("\nCost: {} runs simulated, {} reused from the store; {:.0f} s of runs (each run's wall time, summed "
                   "over every run used, reused ones included: the cost from an empty store, swollen where the cores "
                   "were shared); {:.0f} CPU s in this process (the runs simulated here and the loop; under MPI rank "
                   "0's alone); {:.0f} s wall; {} model replicates per point and parameter value.\n",
                   r.runs_simulated, r.runs_reused, r.run_seconds, r.cpu_seconds, r.wall_seconds,
                   data.model_replicates);
  o << "\nFigures: `data_vs_model.png` (data and model before/after with error bars against each design column), `residuals.png`, `candidate_scores.png`.\n";
}

}  // namespace

void write_calibration_outputs(const DataFile& data, const CalibrationResult& result, const std::filesystem::path& dir,
                               bool plots) {
  std::filesystem::create_directories(dir);
  write_file_atomically(dir / "summary.json", [&](std::ostream& o) { write_summary_json(o, data, result); });
  write_file_atomically(dir / "points.csv", [&](std::ostream& o) { write_points_csv(o, data, result); });
  write_file_atomically(dir / "report.md", [&](std::ostream& o) { write_report_md(o, data, result); });
  if (!plots) return;
  const char* env = std::getenv("GAPFLOW_CALIBRATION_PLOT_SCRIPT");
  const std::string script = env && *env ? env : GAPFLOW_CALIBRATION_PLOT_SCRIPT;
  const std::optional<std::string> python = find_python_with_matplotlib();
  const std::filesystem::path log = dir / "plots.log";
  if (!python || run_program({*python, script, dir.string()}, log) != 0) {
    std::cerr << "calibrate: plots were not drawn (" << (python ? "see " + log.string() : "no python3 with matplotlib") << ")\n";
    return;
  }
  std::filesystem::remove(log);  // kept only when it explains a failure (as the study report does)
}

}  // namespace gapflow
