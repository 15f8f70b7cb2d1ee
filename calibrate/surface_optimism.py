#!/usr/bin/python3
"""How much better the response surface says a calibration fits than direct simulation does at the same
parameters on fresh seeds, per blind pass (a diagnostic; it decides nothing).

    /usr/bin/python3 calibrate/surface_optimism.py [--cases "CASE..."] PASS_DIR [PASS_DIR...]   (--cases: only these calibrations)

Every fitted state is re-scored by direct simulation on fresh seeds (calibrate/fit.hpp): summary.json's
`fitted.chi2` is the surface's chi^2 over the fitted points at the state's parameters, `fitted_fresh.chi2`
the direct simulation's there, each against its own noise (the data's and the surface's or the fresh
runs' standard errors). For the baseline ("before") and the final state ("after"), the median and
quartiles of fresh less surface over the pass's calibrations, beside the median number of fitted
parameters k (the fitted points and measured parameters less the dof). Where the surface were exact and its noise as stated, the
difference would average about 2k: the fit takes about k from the surface's chi^2 (it is minimised
there) and the parameters' estimation error adds about k to the fresh one; and a little more because
the fresh runs' variance at each point is estimated from their few replicates (R: summary.json
"model_replicates"), which raises a chi^2 on average (variance_excess below, from the model's share
of the variance, "model_noise_share"; the surface's variance, pooled over its nodes, is taken as
known). The line gives the median of that expectation, 2k + excess. Well above it, among the readings: the surface's predictions at the fit
lie closer to the data than the model's do (optimism: a fit that found where the surface's own
errors happen to meet the data; profiles read off it too narrow), or the surface states larger
standard errors than its predictions have (an effect term's variance added to the surface's as if
independent, though the two share the nodes' runs; profiles too wide). The held-out points tell
these apart in part: they are not fitted, so a fit's optimism does not reach them; their difference
per point (fresh less surface over the held-out points, median) is given beside. In a state that
misfits, as a baseline without a planted effect, the residual dominates both and the difference can
be of either sign.
"""
import json
import math
import statistics
import sys

from blind_pass import calibrations, require_cases, take_cases


def variance_excess(n, share, replicates, steps=20000):
    """How much a chi^2 over n points rises on average when the model's part of each point's variance (a
    share of the total) is estimated from `replicates` runs: n (E[1 / (1 - share + share Y/nu)] - 1), Y a
    chi^2 variable of nu = replicates - 1 degrees of freedom (normal runs), integrated numerically
    (midpoint rule over Y up to nu + 40 sqrt(2 nu)). With share 1 it is n 2/(nu - 2) for nu > 2."""
    nu = replicates - 1
    if nu < 1 or not 0 <= share <= 1:
        return math.nan
    top = nu + 40 * math.sqrt(2 * nu)
    h = top / steps
    log_norm = (nu / 2) * math.log(2) + math.lgamma(nu / 2)
    mean = 0.0
    for j in range(steps):
        y = (j + 0.5) * h
        density = math.exp((nu / 2 - 1) * math.log(y) - y / 2 - log_norm)
        mean += density * h / (1 - share + share * y / nu)
    return n * (mean - 1)


def differences(pass_dir, state, cases=None):
    """[(fresh chi2 less surface chi2, its expectation 2k + variance_excess, the same per held-out point or
    None)] over the pass's calibrations with both."""
    out = []
    for _, path in calibrations(pass_dir, cases=cases):
        with open(path) as f:
            summary = json.load(f)
        s = summary.get(state, {})
        surface, fresh = s.get("fitted", {}), s.get("fitted_fresh", {})
        if surface.get("chi2") is None or fresh.get("chi2") is None:
            continue
        # A measured free parameter is one more fitted datum: in the dof, not in n.
        k = surface["n"] + len(summary.get("measured_free", [])) - surface["dof"]
        held, held_fresh = s.get("held_out", {}), s.get("held_out_fresh", {})
        per_held = ((held_fresh["chi2"] - held["chi2"]) / held["n"]
                    if held.get("chi2") is not None and held_fresh.get("chi2") is not None and held.get("n") else None)
        share = summary.get("model_noise_share")
        excess = variance_excess(surface["n"], share, summary.get("model_replicates", 0)) if share is not None else 0.0
        out.append((fresh["chi2"] - surface["chi2"], 2 * k + excess, per_held))
    return out


def line(name, pairs):
    if not pairs:
        return f"{name}: none re-scored"
    diffs = sorted(d for d, _, _ in pairs)
    quartiles = statistics.quantiles(diffs, n=4) if len(diffs) >= 2 else [diffs[0]] * 3
    expected = statistics.median(e for _, e, _ in pairs)
    held = [h for _, _, h in pairs if h is not None]
    held_text = f"; per held-out point median {statistics.median(held):+.2f}" if held else ""
    return (f"{name}: fresh less surface chi2 median {quartiles[1]:+.1f} (quartiles {quartiles[0]:+.1f}, "
            f"{quartiles[2]:+.1f}; {len(diffs)} calibrations), expected about {expected:+.1f}{held_text}")


def main(args):
    cases = take_cases(args)
    if not args:
        print('usage: surface_optimism.py [--cases "CASE..."] PASS_DIR [PASS_DIR...]', file=sys.stderr)
        return 2
    for pass_dir in args:
        require_cases(pass_dir, cases)
    for pass_dir in args:
        print(pass_dir + (f" (the {len(cases)} cases asked)" if cases is not None else ""))
        for state, name in (("before", "  baseline"), ("after", "  final")):
            print(line(name, differences(pass_dir, state, cases)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
