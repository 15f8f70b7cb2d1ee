#include "calibrate/calibration.hpp"

#include "calibrate/candidate_scores.hpp"
#include "calibrate/decisions.hpp"
#include "calibrate/effect_catalogue.hpp"
#include "calibrate/effect_responses.hpp"
#include "calibrate/error_measures.hpp"
#include "calibrate/fit.hpp"
#include "calibrate/noise_notes.hpp"
#include "calibrate/surface_noise.hpp"
#include "common/cpu_time.hpp"
#include "common/statistics.hpp"
#include "common/toml_strict.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <map>
#include <optional>

namespace gapflow {

namespace {

class Loop {
 public:
  Loop(const DataFile& data, const CalibrationDef& def, Evaluator& ev, CalibrationResult& out)
      : data_(data), def_(def), ev_(ev), out_(out), responses_(data, def, ev, [this](const std::string& s) { say(s); }),
        n_free_(static_cast<int>(data.free.size())) {}
  Loop(const Loop&) = delete;  // responses_ reports through a lambda holding `this`
  Loop& operator=(const Loop&) = delete;

  void say(const std::string& line) {
    out_.log.push_back(line);
    std::cerr << "calibrate: " << line << "\n";
  }

  const Candidate* find(const Round& round, const std::string& name) const {
    for (const Candidate& c : round.candidates)
      if (c.effect == name) return &c;
    return nullptr;
  }

  // What an added effect stands for: its |cos| group and, if it is the best, its rivals.
  std::vector<std::string> group_of(const Round& round, const Candidate& c) const {
    std::vector<std::string> out{c.effect};
    auto add = [&](const std::vector<std::string>& names) {
      for (const std::string& n : names)
        if (std::find(out.begin(), out.end(), n) == out.end()) out.push_back(n);
    };
    for (const auto& g : round.groups)
      if (std::find(g.begin(), g.end(), c.effect) != g.end()) add(g);
    if (c.effect == round.best) add(round.rivals);
    return out;
  }

  // Rounds of attribution (steps 2-4 of calibration.hpp), from the baseline's state.
  void attribute(const BaselineFit& base, Surface& surface, ModelState& state) {
    base_ = &base;
    std::vector<EffectTerm> terms;
    const Reference baseline = EffectResponses::baseline_reference(base);
    const Reference signature_ref =
        def_.independent_signatures ? responses_.on_own_seeds(baseline, data_.seed + def_.signature_seed_offset) : baseline;
    std::vector<Candidate> cands = responses_.signatures(signature_ref, terms);
    std::optional<Reference> reference = baseline;  // where the next effect's response is measured
    for (int round_no = 0; round_no < def_.max_effects; ++round_no) {
      Round round = score_candidates(data_, def_, cands, state, surface);
      const Candidate* best = round.best.empty() ? nullptr : find(round, round.best);
      if (!worth_trying(round, state, best, fresh_held_out_p(state, surface))) break;
      if (!reference) reference = responses_.reference_with(base, state.params, surface.effects);
      Trial trial = contest(round, terms, *reference, surface, state);
      const Candidate chosen = *find(round, round.best);
      judge(trial, chosen, state);
      if (trial.verdict == Keep::keep) {
        round.decision = added_text(chosen, round, trial, state.bic);
        say(round.decision);
        out_.rounds.push_back(std::move(round));
        accept(chosen, trial, cands);
        surface = trial.surface, state = trial.after, reference.reset();
        continue;
      }
      round.decision = rejected_text(chosen, trial);
      say(round.decision);
      out_.rounds.push_back(std::move(round));
      // Forward selection adds one effect at a time and fails where the first of two effects,
      // alone, makes the points the second one explains worse (blind pass 6, two-drag-gap: a
      // gap offset cut BIC from 1545 to 254 and raised the held-out chi^2 from 945 to 1226).
      // With decisive evidence for the first, the pair is fitted and tested as one step.
      const bool pair_possible = round_no + 1 < def_.max_effects && trial.verdict == Keep::held_out_worse &&
                                 decisive(trial.evidence, def_.decisive_bic);
      if (!pair_possible || !try_pair(base, chosen, trial, cands, terms, surface, state)) break;
      ++round_no;
      reference.reset();
    }
    refresh_added_sizes(surface, state);
    record_size_correlations(surface);
  }

 private:
  struct Trial {
    Surface surface;        // with the effect's term
    EffectFit fit;          // its size, with everything else, on that surface
    ModelState after;
    KeepEvidence evidence;  // against the state it must beat
    Keep verdict = Keep::bic_not_better;
  };

  // The held-out points' chi^2 p at `state` for rule 1's held-out route: fresh seeds, the fitted
  // parameters' uncertainty carried to them (the final verdict's own test: where the loop stops in
  // this state, the verdict reads these runs again, so a route that fired and was rejected leaves
  // the verdict "unexplained" on the same evidence). 1 where the route is off, not needed, or there
  // are no held-out points.
  double fresh_held_out_p(const ModelState& state, const Surface& surface) {
    if (!def_.held_out_route || state.fitted.chi.p < def_.alpha) return 1.0;
    const Prediction fresh =
        ev_.evaluate({state.params}, data_.seed + def_.fresh_seed_offset, data_.model_replicates).front();
    return held_out_fit_aware(data_, surface, state, fresh).p;
  }

  // Whether the round looks for an effect (decisions.hpp); if not, its decision is recorded,
  // prefixed by `context` (a pair's second round names the effect in place). `held_out_p`: the
  // held-out points' chi^2 p at `state` (1: not used).
  bool worth_trying(Round& round, const ModelState& state, const Candidate* best, double held_out_p,
                    const std::string& context = "") {
    const double p = state.fitted.chi.p;
    switch (should_attribute(p, best != nullptr, best ? best->p_adjusted : 1.0, def_.alpha, def_.decisive_score_p,
                             held_out_p)) {
      case Attribute::yes: return true;
      case Attribute::decisive_score:
        say(fmt::format("{}the residual's chi2 is within the noise (p = {:.3g}) but {}'s score is decisive (adjusted p = "
                        "{:.3g} < {:.3g}): tried", context, p, best->effect, best->p_adjusted, def_.decisive_score_p));
        return true;
      case Attribute::held_out_residual:
        say(fmt::format("{}the fitted points are within the noise (chi2 p = {:.3g}) but the held-out points are not "
                        "(fresh seeds, chi2 p = {:.3g}): {} (adjusted p = {:.3g}) tried",
                        context, p, held_out_p, best->effect, best->p_adjusted));
        return true;
      case Attribute::consistent_with_noise:
        round.decision = best ? fmt::format("the residual is consistent with the noise (chi2 p = {:.3g}): nothing to "
                                            "explain (best candidate {}: adjusted p = {:.3g})", p, best->effect, best->p_adjusted)
                              : fmt::format("the residual is consistent with the noise (chi2 p = {:.3g})", p);
        break;
      case Attribute::nothing_visible: round.decision = "no catalogue effect is visible in this design"; break;
      case Attribute::nothing_significant:
        round.decision = fmt::format(
            "no effect's score is significant (best {}: adjusted p = {:.3g}) although {}", best->effect, best->p_adjusted,
            p < def_.alpha ? fmt::format("the residual is not consistent with the noise (chi2 p = {:.3g})", p)
                           : fmt::format("the held-out points are not consistent with the noise (fresh seeds, chi2 p = "
                                         "{:.3g}; the fitted points' chi2 p = {:.3g})", held_out_p, p));
        break;
    }
    round.decision = context + round.decision;
    say(round.decision);
    out_.rounds.push_back(std::move(round));
    return false;
  }

  // Which candidate the round tries (decisions.hpp, rule 4): with one significant candidate,
  // the best score; with more, each fitted in full and the lowest BIC. Sets round.best, .fits
  // and .rivals accordingly; returns the chosen one's fitted trial (not yet judged). With
  // alternatives asked for (rule 5), the other significant candidates are fitted too, and
  // round.alternatives names those that alone leave the fitted points within the noise.
  Trial contest(Round& round, const std::vector<EffectTerm>& terms, const Reference& ref, const Surface& surface,
                const ModelState& state) {
    const int compared = std::max(def_.contenders, 1);  // rule 4 chooses among the first this many
    // Rule 5 asks only where the fitted points are beyond the noise at the round's start: where they
    // pass already (rule 1's decisive-score and held-out routes) every alternative would pass too.
    const bool ask_alternatives = def_.alternatives > 0 && state.fitted.chi.p < def_.alpha;
    const std::vector<const Candidate*> picked =
        significant_picks(round, ask_alternatives ? std::max(compared, 1 + def_.alternatives) : compared);
    // At most one picked (one asked, or one significant), or the best not among them (a route of rule 1's options).
    if (picked.size() < 2)
      return fit_trial(*find(round, round.best), terms, ref, surface, state);
    std::vector<Trial> trials;
    for (const Candidate* c : picked) {
      trials.push_back(fit_trial(*c, terms, ref, surface, state));
      const Trial& t = trials.back();
      round.fits.push_back({c->effect, t.fit.params.get(c->key, c->neutral), t.after.bic, at_neutral(t, *c),
                            t.after.fitted.chi});
    }
    const int tried = compared >= 2 ? choose_among_fits(round, compared) : 0;  // else the best score
    if (ask_alternatives) name_alternatives(round, tried);
    say(contest_line(round, ask_alternatives));
    return std::move(trials[static_cast<std::size_t>(tried)]);
  }

  // The visible candidates rule 4 (and rule 5) fit in full: the significant ones, up to `asked`,
  // best scores first, the round's best first among equal scores. Empty where the best is not
  // among them.
  std::vector<const Candidate*> significant_picks(const Round& round, int asked) const {
    std::vector<const Candidate*> visible;
    std::vector<double> score, p_adjusted;
    for (const Candidate& c : round.candidates)
      if (c.visible) visible.push_back(&c), score.push_back(c.score.statistic), p_adjusted.push_back(c.p_adjusted);
    std::vector<const Candidate*> picked;
    for (int m : contenders(score, p_adjusted, def_.alpha, asked)) picked.push_back(visible[static_cast<std::size_t>(m)]);
    const auto best = std::find_if(picked.begin(), picked.end(), [&](const Candidate* c) { return c->effect == round.best; });
    if (best == picked.end()) return {};
    std::rotate(picked.begin(), best, best + 1);
    return picked;
  }

  // Rule 4 among the first `compared` of round.fits: sets round.best and round.rivals (the fits'
  // rivals, then the score's rivals the fits did not reach); returns the winner's index.
  int choose_among_fits(Round& round, int compared) const {
    const std::size_t n = std::min(round.fits.size(), static_cast<std::size_t>(compared));
    std::vector<double> bic;
    std::vector<bool> eligible;
    for (std::size_t i = 0; i < n; ++i) bic.push_back(round.fits[i].bic), eligible.push_back(!round.fits[i].at_neutral);
    const FitChoice choice = choose_by_fit(bic, eligible, chi_square_quantile(1 - def_.alpha, 1));
    std::vector<std::string> rivals;
    for (int r : choice.rivals) rivals.push_back(round.fits[static_cast<std::size_t>(r)].effect);
    for (const std::string& name : round.rivals)
      if (std::none_of(round.fits.begin(), round.fits.begin() + static_cast<std::ptrdiff_t>(n),
                       [&](const ContenderFit& f) { return f.effect == name; }))
        rivals.push_back(name);
    round.rivals = rivals;
    round.best = round.fits[static_cast<std::size_t>(choice.winner)].effect;
    return choice.winner;
  }

  // Rule 5: round.alternatives, the fits other than the one tried that are not excluded.
  void name_alternatives(Round& round, int tried) const {
    std::vector<double> fitted_p;
    std::vector<bool> eligible;
    for (const ContenderFit& f : round.fits) fitted_p.push_back(f.fitted.p), eligible.push_back(!f.at_neutral);
    for (int a : alternatives_not_excluded(fitted_p, eligible, tried, def_.alpha))
      round.alternatives.push_back(round.fits[static_cast<std::size_t>(a)].effect);
  }

  // The contest's log line: every full fit, the one tried and (rule 5) what is not excluded in its place.
  std::string contest_line(const Round& round, bool ask_alternatives) const {
    std::vector<std::string> listed;
    for (const ContenderFit& f : round.fits)
      listed.push_back(fmt::format("{} {:.4g} (BIC {:.1f}, fitted chi2 p {:.3g}{})", f.effect, f.value, f.bic,
                                   f.fitted.p, f.at_neutral ? ", at neutral" : ""));
    const auto significant = std::count_if(round.candidates.begin(), round.candidates.end(),
                                           [&](const Candidate& c) { return c.visible && c.p_adjusted < def_.alpha; });
    std::string line = fmt::format("{} candidates significant, {} fitted in full: {}; tried: {}", significant,
                                   round.fits.size(), fmt::join(listed, ", "), round.best);
    if (ask_alternatives)
      line += round.alternatives.empty()
                  ? "; no other, in its place, leaves the fitted points within the noise"
                  : fmt::format("; not excluded in its place (the fitted points within the noise with it instead): {}",
                                fmt::join(round.alternatives, ", "));
    return line;
  }

  // fit_trial, then judge.
  Trial try_effect(const Candidate& c, const std::vector<EffectTerm>& signature_terms, const Reference& ref,
                   const Surface& surface, const ModelState& from, const ModelState& against) {
    Trial t = fit_trial(c, signature_terms, ref, surface, from);
    judge(t, c, against);
    return t;
  }

  // The candidate's response measured at the reference (at the baseline with shared signatures:
  // its signature's term with the refinement sizes; with the signatures on seeds of their own, or
  // with effects added: every size measured anew), fitted jointly with everything in `surface`
  // from `from`.
  Trial fit_trial(const Candidate& c, const std::vector<EffectTerm>& signature_terms, const Reference& ref,
                  const Surface& surface, const ModelState& from) {
    Trial t;
    t.surface = surface;
    if (surface.effects.empty() && !def_.independent_signatures) {
      EffectTerm term = *std::find_if(signature_terms.begin(), signature_terms.end(),
                                      [&](const EffectTerm& x) { return x.effect == c.effect; });
      responses_.refine(term, c, ref);
      t.surface.effects.push_back(std::move(term));
    } else {
      // Signatures on seeds of their own serve the score, the visibility and the step; the
      // fitted response is measured anew against the baseline's runs, all its sizes paired alike
      // (until 667bb64 the signature's own-seed sizes were kept beside baseline-paired ones).
      // Baseline pairing largely cancels the nodes' noise in the prediction, but shares it with the
      // residual in the linearised size (effect_responses.hpp, "Shared noise"); pass 20 replayed
      // (not blind) did not tell this from pairing every size with the own seeds (cdf64f9).
      t.surface.effects.push_back(responses_.measure_term(c, ref));
    }
    const EffectDef& e = *find_effect(c.effect);
    const ParameterSet start = from.params.with(e.key, std::clamp(c.neutral + c.score.estimate, e.lo, e.hi));
    const int k = n_free_ + static_cast<int>(t.surface.effects.size());
    t.fit = fit_effect(data_, t.surface, start, t.surface.effects.size() - 1, k);
    if (t.fit.restarted)
      say(fmt::format("{}: the first fit stopped at a local minimum; restarted from the profile scan's best value", e.name));
    // The response holds where it was measured, and the surface only between its nodes: a fit that
    // moved the free parameters nearer another grid node than the one the response was measured
    // around, or stopped at its surface's bound where the grid goes further, has its effect measured
    // again at the grid nodes nearest it, on the surface through the grid nodes around it (the
    // baseline's runs), and is repeated from where it stopped. A missing effect pulls the baseline's
    // free parameters away from their truth, and the effect's fit pulls them back, often beyond the
    // baseline's surface: bounded by it, a size comes out toward neutral
    // (tests/test_calibration_synthetic.cpp). One free parameter: up to three moves (the surface's
    // five nodes follow the fit); two or three: the surface spans the whole grid already, one.
    // The trial is then judged against a state on another surface: each BIC is its data's deviance
    // from its own surface, whose standard errors differ a little from window to window.
    const int moves = n_free_ == 1 ? 3 : 1;
    ParameterSet anchor = ref.anchor;
    for (int move = 0; move < moves && must_move(anchor, t); ++move) {
      say(fmt::format("{}: the fit moved the free parameters to {}; its response is measured again at the grid nodes "
                      "nearest, on the surface around them", e.name, free_label(t.fit.params)));
      const Reference near = responses_.reference_with(*base_, t.fit.params, surface.effects);
      t.surface = surface_around(data_, *base_, t.fit.params);
      t.surface.effects = surface.effects;
      t.surface.effects.push_back(responses_.measure_term(c, near));
      const ParameterSet first = t.fit.params;
      t.fit = fit_effect(data_, t.surface, first, t.surface.effects.size() - 1, k);
      if (t.fit.restarted) say(fmt::format("{}: the re-fit restarted from the profile scan's best value", e.name));
      say(fmt::format("{}: re-fitted on the response measured there: {} = {:.4g} (was {:.4g}), {}", e.name, e.key,
                      t.fit.params.get(e.key, c.neutral), first.get(e.key, c.neutral), free_label(t.fit.params)));
      anchor = near.anchor;
    }
    if (must_move(anchor, t))
      say(fmt::format("{}: left at {} after {} move(s), its response measured around {}", e.name,
                      free_label(t.fit.params), moves, free_label(anchor)));
    t.after = make_state(data_, t.fit.params, t.surface.predict(t.fit.params, data_), k);
    return t;
  }

  // Whether a trial's fit must be repeated where it stopped: nearest another grid node than `anchor`
  // (where its response was measured), or on its surface's bound where the grid goes further.
  bool must_move(const ParameterSet& anchor, const Trial& t) const {
    return !measured_near(anchor, t.fit.params) || at_inner_bound(t.surface, *base_, t.fit.params);
  }

  // Whether `fitted` is nearest the same grid node as `anchor`, the point a response was measured around.
  bool measured_near(const ParameterSet& anchor, const ParameterSet& fitted) const {
    return nearest_same_node(base_->grid, base_->surface, fitted, anchor);
  }

  std::string free_label(const ParameterSet& p) const {
    std::vector<std::string> parts;
    for (const std::string& key : base_->surface.keys) parts.push_back(fmt::format("{} = {:.4g}", key, p.get(key, 0)));
    return fmt::format("{}", fmt::join(parts, ", "));
  }

  // At its neutral value (within 1e-3 of its range) the effect changes nothing.
  static bool at_neutral(const Trial& t, const Candidate& c) {
    const EffectDef& e = *find_effect(c.effect);
    return std::abs(t.fit.params.get(e.key, c.neutral) - c.neutral) <= 1e-3 * (e.hi - e.lo);
  }

  // The keep test of a fitted trial against the state `against`: t.evidence, t.verdict.
  void judge(Trial& t, const Candidate& c, const ModelState& against) {
    // The held-out test by direct simulation, not on the surface: both parameter sets run
    // on seeds of their own (common to both, so that their difference is not the packing;
    // not the final re-score's: with the held-out route those decided that the round looks,
    // and the keep test must not read the same noise again).
    // On the surface a held-out point's prediction carries the finite-difference noise of
    // the effect's measured response there, which can outweigh its data's error.
    const HeldOutCheck held = held_out_check(data_, def_, ev_, against.params, t.fit.params);
    t.evidence = {against.bic, t.after.bic, held.n, held.before, held.after, at_neutral(t, c)};
    t.verdict = keep_verdict(t.evidence, def_.decisive_bic);
  }

  // After `first` was vetoed by the held-out test on decisive BIC evidence: the best candidate
  // against the residual `first` leaves, measured with `first` in place, fitted with it, and
  // the pair tested against the state before either. True when the pair was added.
  bool try_pair(const BaselineFit& base, const Candidate& first, const Trial& one, std::vector<Candidate>& cands,
                const std::vector<EffectTerm>& terms, Surface& surface, ModelState& state) {
    std::vector<Candidate> rest;
    for (const Candidate& c : cands)
      if (c.effect != first.effect) rest.push_back(c);
    Round round = score_candidates(data_, def_, rest, one.after, one.surface);
    const Candidate* best = round.best.empty() ? nullptr : find(round, round.best);
    const std::string context = fmt::format("with {} in place (a pair): ", first.effect);
    if (!worth_trying(round, one.after, best, 1.0, context)) return false;  // a pair: the fitted points only
    const Candidate second = *best;
    const Reference ref = responses_.reference_with(base, one.fit.params, one.surface.effects);
    const Trial two = try_effect(second, terms, ref, one.surface, one.after, state);
    // The pair is one step against the state before either, and the second effect must also
    // earn its place beside the first: BIC lower than the first's alone.
    const bool second_needed = two.after.bic < one.after.bic;
    if (two.verdict != Keep::keep || !second_needed) {
      round.decision = context + rejected_text(second, two) +
                       (second_needed ? "" : fmt::format("; BIC with {} alone {:.1f}", first.effect, one.after.bic));
      say(round.decision);
      out_.rounds.push_back(std::move(round));
      return false;
    }
    round.decision = context + added_text(second, round, two, state.bic) +
                     fmt::format("; fitted jointly with {} = {:.4g} (BIC and held-out chi2 against the state before "
                                 "either; BIC with {} alone {:.1f})",
                                 first.effect, two.fit.params.get(first.key, first.neutral), first.effect, one.after.bic);
    say(round.decision);
    out_.rounds.push_back(std::move(round));
    Round& first_round = out_.rounds[out_.rounds.size() - 2];
    first_round.decision += fmt::format("; kept as a pair with {} (next round)", second.effect);
    accept_as(first, first_round, two.fit.params, one.fit.interval, cands);
    accept(second, two, cands);
    surface = two.surface, state = two.after;
    return true;
  }

  void accept(const Candidate& c, const Trial& t, std::vector<Candidate>& cands) {
    accept_as(c, out_.rounds.back(), t.fit.params, t.fit.interval, cands);
  }

  // `round`: the one `c` was tried in (its group and alternatives).
  void accept_as(const Candidate& c, const Round& round, const ParameterSet& fitted, const ProfileInterval& interval,
                 std::vector<Candidate>& cands) {
    out_.effects.push_back({c.effect, c.key, group_of(round, c),
                            c.effect == round.best ? round.alternatives : std::vector<std::string>{}, c.neutral,
                            fitted.get(c.key, c.neutral), interval.lo, interval.hi,
                            interval.bounded_lo && interval.bounded_hi});
    cands.erase(std::remove_if(cands.begin(), cands.end(), [&](const Candidate& x) { return x.effect == c.effect; }),
                cands.end());
  }

  // An effect added in an earlier round moves when a later one is fitted with it (and a pair's
  // first effect has only its solo fit's interval): every added effect's size and profile
  // interval are taken again on the final surface. `out_.effects[j]` is `surface.effects[j]`:
  // both grow by one per effect kept, in the same order. Where the re-fit's profile scan finds a
  // lower deviance than the state's, the state moves there (and the log says so), so that the
  // reported value is the interval's own estimate.
  void refresh_added_sizes(const Surface& surface, ModelState& state) {
    if (out_.effects.size() < 2) return;
    const int k = n_free_ + static_cast<int>(surface.effects.size());
    for (std::size_t j = 0; j < out_.effects.size(); ++j) {
      AddedEffect& a = out_.effects[j];
      const EffectFit f = fit_effect(data_, surface, state.params, j, k);
      if (f.restarted) {
        say(fmt::format("{}: the final re-fit found a lower deviance from the profile scan's best value", a.effect));
        state = make_state(data_, f.params, surface.predict(f.params, data_), k);
      }
      a.value = f.params.get(a.key, a.neutral);
      a.lo95 = f.interval.lo, a.hi95 = f.interval.hi, a.interval_bounded = f.interval.bounded_lo && f.interval.bounded_hi;
    }
    say(fmt::format("the added effects re-taken on the final surface: {}", state.params.label()));
  }

  // Each added effect's sizes' correlation as its final term counts it.
  void record_size_correlations(const Surface& surface) {
    for (AddedEffect& a : out_.effects)
      for (const EffectTerm& t : surface.effects)
        if (t.effect == a.effect) a.size_correlation = t.neighbour_correlation();
  }

  std::string added_text(const Candidate& c, const Round& round, const Trial& t, double bic_before) const {
    const std::vector<std::string> group = group_of(round, c);
    const EffectDef& e = *find_effect(c.effect);
    return fmt::format("added {}{} = {:.4g} {} [{:.4g}, {:.4g}] (adjusted p = {:.3g}); BIC {:.1f} -> {:.1f}; "
                       "held-out chi2 (keep-test seeds) {:.1f} -> {:.1f}",
                       c.effect, group.size() > 1 ? fmt::format(" (for the group {})", fmt::join(group, ", ")) : "",
                       t.fit.params.get(c.key, c.neutral), e.unit, t.fit.interval.lo, t.fit.interval.hi, c.p_adjusted,
                       bic_before, t.after.bic, t.evidence.held_before, t.evidence.held_after);
  }

  static std::string rejected_text(const Candidate& c, const Trial& t) {
    return fmt::format("candidate {} (adjusted p = {:.3g}) rejected{}: BIC {:.1f} -> {:.1f}, held-out chi2 "
                       "(keep-test seeds) {:.1f} -> {:.1f}",
                       c.effect, c.p_adjusted, t.verdict == Keep::at_neutral ? " (fitted at its neutral value)" : "",
                       t.evidence.bic_before, t.evidence.bic_after, t.evidence.held_before, t.evidence.held_after);
  }

  const DataFile& data_;
  const CalibrationDef& def_;
  Evaluator& ev_;
  CalibrationResult& out_;
  EffectResponses responses_;
  int n_free_;
  const BaselineFit* base_ = nullptr;  // set by attribute()
};

// The surface window a state's prediction was read from (ModelState window_*).
void record_window(ModelState& state, const Surface& surface) {
  state.window_keys = surface.keys;
  state.window_lo = surface.lo;
  state.window_hi = surface.hi;
}

}  // namespace

CalibrationResult calibrate(const DataFile& data, const CalibrationDef& def, Evaluator& ev) {
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = process_cpu_seconds();
  CalibrationResult out;
  out.data_name = data.name;
  out.model = to_string(def.model);
  Loop loop(data, def, ev, out);
  const int n_free = static_cast<int>(data.free.size());

  // 1. Baseline fit, on the response surface.
  const BaselineFit base = fit_baseline(data, def, ev, [&](const std::string& s) { loop.say(s); });
  Surface surface = base.surface;
  out.before = make_state(data, base.params, surface.predict(base.params, data), n_free);
  record_window(out.before, surface);
  loop.say(fmt::format("baseline {}: chi2/nu = {:.2f} (p = {:.3g}) on {} fitted points; held-out RMS {:.2f} sigma",
                       base.params.label(), out.before.fitted.chi.per_dof(), out.before.fitted.chi.p,
                       out.before.fitted.n, out.before.held_out.rms_whitened));

  out.model_noise_share = model_noise_share(data, out.before.prediction);
  loop.say(model_noise_text(out.model_noise_share, data.model_replicates));
  const SurfaceNoiseCheck surface_noise = surface_noise_check(data, base);
  out.surface_noise_ratio = surface_noise.all.understated;
  out.node_correlation = surface_noise.all.correlation;
  out.surface_noise_counted = surface_noise.all.counted;
  loop.say(surface_noise_text(surface_noise));

  const std::vector<std::string> correlations = shared_run_correlations(data, base);
  if (!correlations.empty())
    loop.say(fmt::format("observables on the same runs, correlation of their replicate values (chi^2 treats them as "
                         "independent): {}", fmt::join(correlations, "; ")));

  // 2.-4. Rounds of attribution (--max-effects 0 is a fit and its errors only: nothing is measured).
  ModelState state = out.before;
  if (def.max_effects > 0) loop.attribute(base, surface, state);
  out.after = state;
  record_window(out.after, surface);
  out.shared_covariance_bound = surface.shared_covariance_bound(out.after.params);
  if (out.shared_covariance_bound.pairs > 0)
    loop.say(fmt::format("final state: the quadratic's covariance with the added effects' shifts held at its "
                         "Cauchy-Schwarz bound at {} of {} (point, effect) pairs",
                         out.shared_covariance_bound.at_bound, out.shared_covariance_bound.pairs));

  // An alternative that was added itself (in a later round) stands beside the effect, not in its place.
  for (AddedEffect& e : out.effects)
    std::erase_if(e.alternatives, [&](const std::string& name) {
      return std::any_of(out.effects.begin(), out.effects.end(), [&](const AddedEffect& a) { return a.effect == name; });
    });

  // Fresh seeds: the fitted parameters before and after, simulated directly on other runs.
  const std::vector<Prediction> fresh =
      ev.evaluate({out.before.params, out.after.params}, data.seed + def.fresh_seed_offset, data.model_replicates);
  out.before.fitted_fresh = error_measures(data, fresh[0], out.before.params, false, n_free);
  out.before.held_out_fresh = error_measures(data, fresh[0], out.before.params, true, n_free);
  const int k_final = n_free + static_cast<int>(out.effects.size());
  out.after.fitted_fresh = error_measures(data, fresh[1], out.after.params, false, k_final);
  out.after.held_out_fresh = error_measures(data, fresh[1], out.after.params, true, k_final);
  out.before.simulated_fresh = fresh[0];
  out.after.simulated_fresh = fresh[1];

  out.held_out_fresh_fit_aware = held_out_fit_aware(data, surface, out.after, fresh[1]);
  FormCheckDef form;
  form.alpha = def.alpha;
  out.form_checks = form_checks(data, surface, out.after, form);
  out.form_differs = form_differs(out.form_checks, def.alpha);
  std::vector<std::string> added;
  for (const AddedEffect& e : out.effects) added.push_back(e.effect);
  out.law_power = lowest_law_power(out.form_checks, added);
  out.law_undetermined = !laws_established(out.form_checks, added, form.power, def.alpha);
  const VerdictEvidence evidence{.attribution_allowed = def.max_effects > 0,
                                 .effects_added = static_cast<int>(out.effects.size()),
                                 .fitted_p_before = out.before.fitted.chi.p,
                                 .fitted_p_after = out.after.fitted.chi.p,
                                 .held_out_n = out.after.held_out_fresh.n,
                                 .held_out_fresh_p = out.held_out_fresh_fit_aware.p,
                                 .alpha = def.alpha,
                                 .law_undetermined = out.law_undetermined,
                                 .alternatives = std::any_of(out.effects.begin(), out.effects.end(),
                                                             [](const AddedEffect& e) { return !e.alternatives.empty(); })};
  out.poor_fit = poor_fit(evidence);
  out.held_out_beyond_noise = held_out_beyond_noise(evidence);
  out.verdict = final_verdict(evidence);
  out.alpha = def.alpha;
  out.contenders = def.contenders;
  out.alternatives = def.alternatives;
  out.decisive_score_p = def.decisive_score_p;
  out.held_out_route = def.held_out_route;
  out.independent_signatures = def.independent_signatures;
  out.runs_simulated = ev.runs_simulated();
  out.runs_reused = ev.runs_reused();
  out.run_seconds = ev.run_seconds();
  out.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.cpu_seconds = process_cpu_seconds() - cpu_start;
  return out;
}

}  // namespace gapflow
