#!/usr/bin/python3
"""How much better the response surface says a calibration fits than direct simulation does at the same
parameters on fresh seeds, per blind pass (a diagnostic; it decides nothing).

    /usr/bin/python3 calibrate/surface_optimism.py PASS_DIR [PASS_DIR...]

Every fitted state is re-scored by direct simulation on fresh seeds (calibrate/fit.hpp): summary.json's
`fitted.chi2` is the surface's chi^2 over the fitted points at the state's parameters, `fitted_fresh.chi2`
the direct simulation's there, each against its own noise (the data's and the surface's or the fresh
runs' standard errors). For the baseline ("before") and the final state ("after"), the median and
quartiles of fresh less surface over the pass's calibrations, beside the median number of fitted
parameters k (the fitted points and measured parameters less the dof). Where the surface were exact and its noise as stated, the
difference would average about 2k: the fit takes about k from the surface's chi^2 (it is minimised
there) and the parameters' estimation error adds about k to the fresh one; a little more (about 1.5 on
44 points where the model is 31 % of the variance) because the fresh runs' variance is estimated
point by point from 6 runs. Well above that, among the readings: the surface's predictions at the fit
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
import statistics
import sys

from blind_pass import calibrations


def differences(pass_dir, state):
    """[(fresh chi2 less surface chi2, fitted parameters, the same per held-out point or None)] over the
    pass's calibrations with both."""
    out = []
    for _, path in calibrations(pass_dir):
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
        out.append((fresh["chi2"] - surface["chi2"], k, per_held))
    return out


def line(name, pairs):
    if not pairs:
        return f"{name}: none re-scored"
    diffs = sorted(d for d, _, _ in pairs)
    quartiles = statistics.quantiles(diffs, n=4) if len(diffs) >= 2 else [diffs[0]] * 3
    k = statistics.median(k for _, k, _ in pairs)
    held = [h for _, _, h in pairs if h is not None]
    held_text = f"; per held-out point median {statistics.median(held):+.2f}" if held else ""
    return (f"{name}: fresh less surface chi2 median {quartiles[1]:+.1f} (quartiles {quartiles[0]:+.1f}, "
            f"{quartiles[2]:+.1f}; {len(diffs)} calibrations), 2k = {2 * k:g}{held_text}")


def main(args):
    if not args:
        print("usage: surface_optimism.py PASS_DIR [PASS_DIR...]", file=sys.stderr)
        return 2
    for pass_dir in args:
        print(pass_dir)
        for state, name in (("before", "  baseline"), ("after", "  final")):
            print(line(name, differences(pass_dir, state)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
