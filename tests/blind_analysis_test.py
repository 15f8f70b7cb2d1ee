#!/usr/bin/env python3
"""The blind study's analysis scripts (calibrate/*.py) on a tiny pass whose answers are known.

A fake pass folder is written from scratch: six twins with their truth/ files and the parts of
summary.json and report.md the scripts read. Each script is run as a user runs it (a subprocess,
`/usr/bin/python3 calibrate/X.py ...`) and its counts are compared with what the fixture was made
to hold. Every assertion fails if a script miscounts: e.g. the visible-but-missed twin, the null
that got an effect, the interval that misses toward neutral, the round a --decisive-score would try.

    /usr/bin/python3 tests/blind_analysis_test.py
"""
import csv
import importlib.util
import json
import math
import os
import sqlite3
import statistics
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

CALIBRATE = Path(__file__).resolve().parent.parent / "calibrate"
STUDIES = Path(__file__).resolve().parent.parent / "studies"


def truth(case, planted, power=None, chi2=None):
    t = {"twin": case, "model": "2d", "seed": 1, "planted": [
        {"name": "free", "key": "particles.friction_particle", "value": 0.40, "neutral": None}] + planted,
         "measured": {"particles.friction_particle": 0.38}}
    if power is not None:
        t["signal"] = {"chi2": chi2, "points": 44, "critical": 7.9, "oracle_power": power}
    return t


def errors(chi2, rms):
    return {"n": 12, "rmse": rms / 10, "rms_whitened": rms, "chi2": chi2, "dof": 12, "p": 0.5, "invalid": 0}


def summary(effects, verdict, rms_before=2.0, rms_after=1.0, fitted_chi2=88.0, fitted_p=0.5, first_round=None):
    """The summary.json fields the scripts read; the free parameter fitted to 0.42 (truth 0.40).
    `first_round`: (effect, adjusted p) of its visible candidates."""
    fitted = {**errors(fitted_chi2, 1.4), "dof": 43, "p": fitted_p}
    rounds = [{"candidates": [{"effect": e, "visible": True, "p_adjusted": p, "estimate": 0.1, "step": 1.0,
                               "score": 1.0} for e, p in first_round]}] if first_round else []
    return {
        "effects": effects, "verdict": verdict, "poor_fit": False, "held_out_beyond_noise": False,
        "before": {"fitted": fitted, "held_out_fresh": errors(48.0, rms_before)},
        "after": {"params": {"particles.friction_particle": 0.42}, "fitted": errors(43.0, 1.0),
                  "held_out_fresh": errors(12.0, rms_after)},
        "measured_free": [{"key": "particles.friction_particle", "measured": 0.38, "se": 0.04}],
        "rounds": rounds, "runs_simulated": 1000, "runs_reused": 200, "run_seconds": 600.0, "wall_seconds": 320.0,
    }


def added(effect, key, value, lo, hi, neutral=0.0, group=None):
    return {"effect": effect, "key": key, "group": group or [effect], "neutral": neutral, "value": value,
            "lo95": lo, "hi95": hi, "interval_bounded": True}


DRAG = {"name": "linear_drag", "key": "particles.drag_per_s", "value": 3.0, "neutral": 0}
SPIN = {"name": "spinning_friction", "key": "particles.spinning_friction_mm", "value": 0.7, "neutral": 0}
ROLL = {"name": "rolling_resistance", "key": "particles.rolling_resistance", "value": 0.002, "neutral": 0.001}
OUTSIDE = {"name": "set", "key": "particles.drag_quadratic_per_m", "value": 4.0, "neutral": 0}

STOPPED = ("Decision: the residual is consistent with the noise (chi2 p = 0.31): nothing to explain "
           "(best candidate spinning_friction: adjusted p = 0.0002).\n")
ROUND_TABLE = """### Round 1

| effect | step | visible (p) | left by the fit | score | p | adjusted p | linearised size | group |
|---|---|---|---|---|---|---|---|---|
| spinning_friction | 0.5 | yes (0) | 80 % | 30.00 | 1e-07 | 1e-06 | -0.2 ± 0.05 | 0 |
| gap_offset | 1.5 | yes (0) | 99 % | 5.00 | 0.02 | 0.2 | 0.1 ± 0.05 | 1 |
"""

# case: (truth, summary, report.md)
CASES = {
    # Found, but its interval [2.5, 2.8] misses the planted 3.0 toward neutral; held-out excess 2 -> 1.
    "drag-low": (truth("drag-low", [DRAG], power=1.0, chi2=170.0),
                 summary([added("linear_drag", DRAG["key"], 2.6, 2.5, 2.8)], "effect found", fitted_chi2=215.0,
                         fitted_p=1e-9, first_round=[("linear_drag", 1e-5)]), ""),
    # Visible in its data (power 0.9) and missed: a round stopped with a best adjusted p of 2e-4.
    "spin-high": (truth("spin-high", [SPIN], power=0.9, chi2=20.0),
                  summary([], "consistent with noise", rms_before=1.0, rms_after=1.0, fitted_chi2=65.0,
                          fitted_p=0.31, first_round=[("spinning_friction", 2e-4)]), STOPPED),
    # Identified only through its group: linear drag tried for {linear_drag, rolling_resistance}.
    # Its form check fired: a false alarm for a catalogue effect, still identified.
    "rolling-high": (truth("rolling-high", [ROLL], power=1.0, chi2=50.0),
                     {**summary([added("linear_drag", DRAG["key"], 1.0, 0.5, 1.5, group=["linear_drag", "rolling_resistance"])],
                                "effect found; its size differs across the design: an effect of another form may be acting",
                                fitted_chi2=95.0, fitted_p=0.01,
                                first_round=[("rolling_resistance", 0.2), ("linear_drag", 0.001)]),
                      "form_differs": True,
                      "form_checks": [{"effect": "linear_drag", "column": "incline_deg", "levels": 3, "statistic": 14.0,
                                       "dof": 2, "rest_dof": 41, "scale": 1.25, "p": 0.005, "p_adjusted": 0.02,
                                       "trend_ordered": True, "spread_level": 0.025, "detectable_spread": 0.904},
                                      {"effect": "linear_drag", "column": "W_over_d", "levels": 3, "statistic": 1.0,
                                       "dof": 2, "rest_dof": 41, "scale": 1.3, "p": 0.7, "p_adjusted": 1.0,
                                       "trend_ordered": True, "spread_level": 0.025, "detectable_spread": None},
                                      {"effect": "linear_drag", "column": "observable", "levels": 4, "statistic": 1.0,
                                       "dof": 3, "rest_dof": 40, "scale": 1.3, "p": 0.8, "p_adjusted": 1.0,
                                       "trend_ordered": False, "spread_level": 0.025, "detectable_spread": None}]}, ""),
    # Invisible (power 0.1) and rightly "none".
    "rolling-low": (truth("rolling-low", [ROLL], power=0.1, chi2=1.0),
                    summary([], "consistent with noise", rms_before=1.0, rms_after=1.0), ""),
    # A null twin that got an effect: a false positive. Its best round asked for a spinning
    # friction below neutral, which the catalogue's range rules out (wrong_direction_rounds).
    "null-1": (truth("null-1", []),
               summary([added("gap_offset", "bottleneck.gap_offset_mm", 0.2, 0.1, 0.3)], "effect found", fitted_chi2=45.0),
               ROUND_TABLE),
    # Outside the catalogue: read as nothing.
    "outside-quadratic-4": (truth("outside-quadratic-4", [OUTSIDE], power=0.05, chi2=1.0),
                            summary([], "consistent with noise", rms_before=1.0, rms_after=1.0), ""),
}


def run(script, *args, cwd=None):
    done = subprocess.run([sys.executable, str(CALIBRATE / script), *map(str, args)], capture_output=True, text=True,
                          cwd=cwd)
    return done.returncode, done.stdout, done.stderr


class BlindAnalysis(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.pass_dir = Path(cls.tmp.name) / "pass"
        (cls.pass_dir / "truth").mkdir(parents=True)
        for case, (t, s, report) in CASES.items():
            (cls.pass_dir / "truth" / f"{case}.json").write_text(json.dumps(t))
            (cls.pass_dir / case).mkdir()
            (cls.pass_dir / case / "summary.json").write_text(json.dumps(s))
            # A stopped round's decision stands twice in a real report (round table and log): counted
            # once. A round table stands once.
            decisions = "".join(line for line in report.splitlines(True) if line.startswith("Decision:"))
            (cls.pass_dir / case / "report.md").write_text(report + decisions)
        # A replay kept in the pass folder (spin-high calibrated again): not one of the pass's twins.
        replay = cls.pass_dir / "replay-spin-high"
        replay.mkdir()
        (replay / "summary.json").write_text((cls.pass_dir / "spin-high" / "summary.json").read_text())
        (replay / "report.md").write_text((cls.pass_dir / "spin-high" / "report.md").read_text())
        code, cls.summary_out, err = run("blind_summary.py", cls.pass_dir)
        assert code == 0, err
        with open(cls.pass_dir / "cases.csv", newline="") as f:
            cls.rows = {r["case"]: r for r in csv.DictReader(f)}

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def test_blind_summary_classifies_each_twin(self):
        r = self.rows
        self.assertEqual(r["drag-low"]["truth"], "linear_drag")
        self.assertEqual(r["drag-low"]["identified"], "True")
        self.assertEqual(r["drag-low"]["tried_planted"], "True")
        self.assertEqual(r["rolling-high"]["identified"], "True")
        self.assertEqual(r["rolling-high"]["tried_planted"], "False")
        self.assertEqual(r["drag-low"]["covered"], "False")
        self.assertEqual(r["spin-high"]["identified"], "False")
        self.assertEqual(r["spin-high"]["visible"], "True")
        self.assertEqual(r["rolling-low"]["visible"], "False")
        self.assertEqual(r["null-1"]["truth"], "none")
        self.assertEqual(r["null-1"]["said"], "gap_offset")
        self.assertEqual(r["outside-quadratic-4"]["truth"], "outside the catalogue")
        self.assertEqual(r["outside-quadratic-4"]["said"], "none")
        self.assertAlmostEqual(float(r["drag-low"]["free_offset"]), 0.02, places=4)

    def test_blind_summary_report_counts(self):
        report = (self.pass_dir / "report.md").read_text()
        self.assertIn("identified (alone, or in a reported group that contains it): 2 of 4 (50 %)", report)
        # rolling-high counts through its group only: linear drag was tried, not the planted rolling resistance.
        self.assertIn("the effect tried is the planted one (not only a member of the group reported): 1 of 2", report)
        self.assertIn("null twins where an effect was added: 1 of 1 (100 %)", report)
        # rolling-high's flag is not a false alarm: linear drag was tried for its group, not the planted effect.
        self.assertIn("form check says differs across the design (false alarms for a catalogue effect; still counted "
                      "as identified): 0 of 1 (0 %)", report)
        self.assertIn("other calibrations the form check flags: rolling-high", report)
        self.assertIn("contain the planted value: 0 of 1 (0 %)", report)
        self.assertIn("visible in their data (oracle power >= 0.8): 3 of 4; of these identified: 2 of 3 (67 %)", report)
        # Excess over the noise sqrt(rms^2 - 1): sqrt(3) = 1.73 before, 0 after, for each of the two found twins.
        self.assertIn("that excess summed over those cases: 3.5 -> 0.0", report)
        self.assertTrue((self.pass_dir / "confusion.png").stat().st_size > 0)
        # The fixture's summaries predate the option's record: the signatures shared the baseline's runs.
        self.assertIn("the signatures sharing the baseline's runs", report)

    def test_visibility_ceiling_counts_from_cases_csv(self):
        code, out, _ = run("visibility_ceiling.py", self.pass_dir, self.pass_dir)
        self.assertEqual(code, 0)
        self.assertIn("identified 2 of 4 (50 %); visible 3 (ceiling 75 %); identified among the visible 2 of 3 (67 %)", out)
        self.assertIn("pooled: identified 4 of 8", out)
        # The exact binomial interval for 4 of 8 (beta quantiles 0.025 of B(4, 5), 0.975 of B(5, 4)).
        self.assertIn("identified share 95 % interval [15.7, 84.3] %", out)
        code, out, _ = run("visibility_ceiling.py", "--by-case", self.pass_dir, self.pass_dir)
        self.assertEqual(code, 0)
        self.assertIn("  drag-low: 2 of 2; visible 2; 2 of 2", out)
        self.assertNotIn("null-1:", out)  # singles only

    def test_rule_1_oracle_matches_a_simulation_of_its_two_gates(self):
        sys.path.insert(0, str(CALIBRATE))
        import numpy as np
        from scipy.stats import chi2
        from visibility_ceiling import at_least, rule1_power
        # The two gates simulated: a residual of 44 whitened components, the signature along the first
        # with noncentrality lambda; the score is that component squared, the chi^2 all of them.
        rng = np.random.default_rng(7)
        critical, dof = chi2.isf(0.05 / 10, 1), 44
        for lam in (0.0, 8.0, 18.0, 40.0):
            r = rng.standard_normal((200000, dof))
            r[:, 0] += np.sqrt(lam)
            both = (r[:, 0] ** 2 > critical) & ((r ** 2).sum(axis=1) > chi2.isf(0.05, dof))
            self.assertAlmostEqual(rule1_power(lam, dof, critical), both.mean(), delta=0.004)
            # --decisive 1e-3: a score beyond the adjusted level 1e-3 (Bonferroni over 10) passes alone.
            decisive = (r[:, 0] ** 2 > critical) & (both | (r[:, 0] ** 2 > chi2.isf(1e-3 / 10, 1)))
            self.assertAlmostEqual(rule1_power(lam, dof, critical, decisive=1e-3), decisive.mean(), delta=0.004)
        # Below either gate's own power: the score alone at lambda 18 passes 0.93 of the time (the oracle's
        # visible), the chi^2 alone 0.522; together they pass less often than the weaker.
        self.assertLess(rule1_power(18.0, dof, critical), 0.522)
        self.assertAlmostEqual(at_least([0.5, 0.5], 1), 0.75)
        self.assertAlmostEqual(at_least([0.5, 0.5], 2), 0.25)
        self.assertAlmostEqual(at_least([0.9, 0.8, 0.7], 3), 0.9 * 0.8 * 0.7)
        # The script sums the single-effect twins' chances (drag-low, spin-high, rolling-high,
        # rolling-low: lambda 170, 20, 50 and 1 with 44 fitted points and a measured friction).
        expected = sum(rule1_power(lam, 44, 7.9) for lam in (170.0, 20.0, 50.0, 1.0))
        code, out, _ = run("visibility_ceiling.py", "--rule-1", self.pass_dir)
        self.assertEqual(code, 0)
        self.assertIn(f"expected identified {expected:.1f} of 4", out)
        # Each twin's chance with its own degrees of freedom: 44 fitted points + 1 measured - 1 free.
        from visibility_ceiling import rule1_chances
        chances = rule1_chances(str(self.pass_dir))
        for got, lam in zip(chances, (170.0, 50.0, 1.0, 20.0)):  # cases.csv order: drag-low, rolling-high, rolling-low, spin-high
            self.assertAlmostEqual(got, rule1_power(lam, 44, 7.9), places=12)
        self.assertNotAlmostEqual(rule1_power(20.0, 43, 7.9), rule1_power(20.0, 44, 7.9), places=3)
        self.assertGreater(expected, 2.0)
        self.assertLess(expected, 3.0)
        # --scale K: every lambda K times (the noise's variance divided by K).
        doubled = sum(rule1_power(2 * lam, 44, 7.9) for lam in (170.0, 20.0, 50.0, 1.0))
        self.assertGreater(doubled, expected + 0.2)
        code, out, _ = run("visibility_ceiling.py", "--rule-1", "--scale", "2", self.pass_dir)
        self.assertEqual(code, 0)
        self.assertIn(f"expected identified {doubled:.1f} of 4", out)
        self.assertEqual(run("visibility_ceiling.py", "--rule-1", "--scale", "-1", self.pass_dir)[0], 2)
        self.assertEqual(run("visibility_ceiling.py", "--rule-1", "--decisive", "0.5", self.pass_dir)[0], 2)
        self.assertEqual(run("visibility_ceiling.py", "--scale", "2", self.pass_dir)[0], 2)  # needs --rule-1
        self.assertGreater(rule1_power(18.0, dof, critical, decisive=1e-3), rule1_power(18.0, dof, critical) + 0.1)

    def test_gates_say_where_each_single_effect_was_won_or_lost(self):
        code, out, _ = run("visibility_ceiling.py", "--gates", "--by-case", self.pass_dir)
        self.assertEqual(code, 0)
        # drag-low past both gates and found; rolling-high past the chi^2 gate with its own score not
        # significant, found through drag's group; spin-high stopped at the chi^2 gate with its score
        # significant; rolling-low stopped with nothing.
        self.assertIn("rule 1's chi^2 gate passed in 2 (50 %), and in those the planted effect's score significant "
                      "in 1; identified 2: 1 of the 1, 1 of the 1 others past the gate, 0 of the 2 stopped at it "
                      "(1 of those with the planted score significant)", out)
        self.assertIn("  spin-high: 1; 0; 0; 0", out)
        # Of the two stopped at the gate, spin-high's best score (its own, adjusted p 2e-4) would be tried
        # by a decisive-score route at 1e-3 and 1e-2, not at 1e-4; rolling-low has no first round.
        self.assertIn("stopped at the gate with the best score's adjusted p < 0.0001: 0 (the planted effect that best score in 0)", out)
        self.assertIn("stopped at the gate with the best score's adjusted p < 0.001: 1 (the planted effect that best score in 1)", out)
        self.assertIn("  rolling-high: 1; 1; 0; 1", out)

    def test_replay_compare_counts_changes_twin_by_twin(self):
        import shutil
        replay = Path(self.tmp.name) / "replay"
        if replay.exists():
            shutil.rmtree(replay)
        shutil.copytree(self.pass_dir, replay)
        with open(replay / "cases.csv", newline="") as f:
            table = list(csv.DictReader(f))
        for r in table:  # the replay's drag-low: held-out RMS/noise after the fit 1.0 -> 3.0 (excess 0 -> 2.83)
            if r["case"] == "drag-low":
                r["heldout_rms_sigma_after"] = "3.0"
        with open(replay / "cases.csv", "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(table[0].keys()))
            w.writeheader()
            w.writerows(table)
        code, out, _ = run("replay_compare.py", self.pass_dir, replay)
        self.assertEqual(code, 0)
        # Found in both: drag-low and rolling-high (through its group; its size is drag's, not the
        # planted rolling resistance's, so only drag-low has a size error: |2.6 - 3| / 3).
        self.assertIn("pass: identified 2 of 4; intervals holding the planted value 0 of 1; nulls with an effect added "
                      "1 of 1; median relative size error 0.133 over 1 (of the planted departure from neutral; 0.133 of the "
                      "planted value); held-out excess after the fit, summed over the 2 cases found in both, 0.0", out)
        self.assertIn("held-out excess after the fit, summed over the 2 cases found in both, 2.8", out)
        self.assertIn("rose in 1, fell in 0, unchanged in 1", out)
        self.assertEqual(run("replay_compare.py", self.pass_dir)[0], 2)

    def test_form_check_table_names_each_smallest_check_and_counts_false_alarms_apart(self):
        code, out, _ = run("form_check_table.py", self.pass_dir, self.pass_dir)
        self.assertEqual(code, 0)
        self.assertIn("| 0.02 (linear_drag split by incline_deg: S 14.0 on 2 dof; rest scale 1.25 on 41 dof) |", out)
        self.assertIn("| drag-low |", out)
        self.assertIn("no check", out)
        self.assertIn("| incline_deg 90 %; W_over_d none; observable no order |", out)
        # rolling-high was found through drag's group: its flag is not a false alarm for a catalogue effect.
        self.assertIn("the planted effect tried, flagged (false alarms for a catalogue effect): 0 of 1 []", out)
        self.assertIn("other calibrations flagged: ['rolling-high']", out)
        self.assertIn("effects or sizes differing from", out)
        self.assertIn(": none", out)

    def test_quadratic_drag_visibility_reads_the_speed_scaling_and_the_checks_power(self):
        import math
        root = Path(self.tmp.name) / "quadratic"
        (root / "pass" / "twins").mkdir(parents=True, exist_ok=True)
        # J_mid exactly as sqrt(sin theta) at one gap (spread 0.429), and an obstruction point and an
        # other observable that must be left out.
        points = [f"[[point]]\nW_over_d = 4.5\nincline_deg = {t}\nshape = \"none\"\nvalue = {100 * math.sqrt(math.sin(math.radians(t)))}\n"
                  for t in (5.0, 8.0, 12.0)]
        points.append("[[point]]\nW_over_d = 4.5\nincline_deg = 12.0\nshape = \"V\"\nvalue = 900.0\n")
        points.append("[[point]]\nW_over_d = 4.5\nincline_deg = 12.0\nshape = \"none\"\nobservable = \"exit_spread\"\nvalue = 0.1\n")
        (root / "pass" / "twins" / "null-1.toml").write_text("[observable]\nkind = \"j_mid\"\n\n" + "\n".join(points))
        case = root / "replay" / "outside-quadratic-16"
        case.mkdir(parents=True, exist_ok=True)
        needed = (math.sqrt(math.sin(math.radians(12))) - math.sqrt(math.sin(math.radians(5)))) / (
            sum(math.sqrt(math.sin(math.radians(t))) for t in (5, 8, 12)) / 3)
        checks = [{"effect": "linear_drag", "column": "incline_deg", "dof": 2, "rest_dof": 41, "p_adjusted": 0.9,
                   "scale": 1.0, "spread_level": 0.025, "detectable_spread": needed},
                  {"effect": "linear_drag", "column": "W_over_d", "dof": 2, "rest_dof": 41, "p_adjusted": 1.0,
                   "scale": 1.0, "spread_level": 0.025, "detectable_spread": 2 * needed}]
        (case / "summary.json").write_text(json.dumps({"form_checks": checks}))
        code, out, err = run("quadratic_drag_visibility.py", root / "pass", root / "replay")
        self.assertEqual(code, 0, err)
        self.assertIn(f"median {needed:.3f} (range {needed:.3f}-{needed:.3f}; sqrt(sin theta) predicts {needed:.3f} "
                      "against the mean", out)
        # At its own detectable spread the check has power 0.8 at the stated noise and more where the
        # residual's scale says the noise is smaller; against the steepest incline's size the spread is
        # smaller (power lower), against the shallowest larger.
        self.assertIn(f"at level 0.025 at the stated noise, F on 2 and 41 dof); adjusted p 0.9; power at the spread a "
                      f"quadratic drag asks for ({needed:.3f}): 0.80 at the stated noise (0.", out)
        self.assertIn("incline's size), 0.80 at the residual's own scale 1.00; power 0.8 there at the stated noise needs "
                      "1.0 x", out)
        low, high = (float(x) for x in out.split("at the stated noise (")[1].split(" against")[0].split(", "))
        self.assertLess(low, 0.8)
        self.assertGreater(high, 0.8)
        checks[0]["detectable_spread"] = 2 * needed  # half the spread seen: lambda / 4
        checks[0]["scale"] = 0.25                    # the noise half the stated: lambda x 4
        (case / "summary.json").write_text(json.dumps({"form_checks": checks}))
        out = run("quadratic_drag_visibility.py", root / "pass", root / "replay")[1]
        self.assertIn("needs 4.0 x the information", out)
        self.assertIn("0.80 at the residual's own scale 0.25", out)
        # Read as another effect: its check along the incline asks nothing of a drag's law, and is not taken.
        other = [dict(checks[0], effect="restitution", detectable_spread=needed)]
        (case / "summary.json").write_text(json.dumps({"form_checks": other, "verdict": "effect found",
                                                       "effects": [{"effect": "restitution"}]}))
        code, _, err = run("quadratic_drag_visibility.py", root / "pass", root / "replay")
        self.assertEqual(code, 2)
        self.assertIn("no check of linear_drag along incline_deg with a detectable spread (added: restitution; "
                      "verdict: effect found)", err)
        checks[0]["detectable_spread"] = None
        (case / "summary.json").write_text(json.dumps({"form_checks": checks}))
        self.assertEqual(run("quadratic_drag_visibility.py", root / "pass", root / "replay")[0], 2)
        self.assertEqual(run("quadratic_drag_visibility.py", root / "replay", root / "replay")[0], 2)  # no null twin
        # Two points at one gap and incline: refused, not silently overwritten.
        twin = root / "pass" / "twins" / "null-1.toml"
        twin.write_text(twin.read_text() + "\n" + points[0])
        self.assertEqual(run("quadratic_drag_visibility.py", root / "pass", root / "replay")[0], 2)

    def test_interval_sides_says_toward_neutral(self):
        code, out, _ = run("interval_sides.py", self.pass_dir)
        self.assertEqual(code, 0)
        self.assertIn("0 intervals hold the planted value; missed toward neutral 1, away from it 0", out)
        # The fit left the friction at 0.42, its measurement 0.38 +- 0.04: +1.0 se.
        self.assertIn("toward: drag-low (particles.drag_per_s 2.6 for 3; free parameter +1.0 se from its measurement)", out)
        self.assertIn("toward: 1 interval(s); free parameter more than 2 se from its measurement in 0; "
                      "median |distance| 1.00 se", out)

    def test_interval_coverage_counts_planted_keys_and_the_miss_in_standard_errors(self):
        code, out, _ = run("interval_coverage.py", self.pass_dir)
        self.assertEqual(code, 0)
        # drag-low: [2.5, 2.8] around 2.6 for a planted 3.0: the half toward it 0.2 = 1.96 se, the miss 0.4 = 3.92 se.
        # The gap offset of null-1 and rolling-high's linear drag were not planted: not counted.
        self.assertIn("| particles.drag_per_s | 1 | 0 (0 %; 0-", out)
        self.assertIn("| 1 / 0 | 3.92 | - |", out)
        self.assertIn("| all | 1 | 0 (0 %;", out)
        self.assertNotIn("gap_offset", out)
        # Its size 2.6 for 3.0 (0.87 of the planted departure from 0), the friction fitted 0.42 for 0.40.
        self.assertIn("| particles.drag_per_s | 1 | 0.87 | +0.020 | - | -0.020 | - |", out)  # measured 0.38
        self.assertEqual(run("interval_coverage.py", self.pass_dir / "nothing")[0], 2)
        # From 20 intervals on, the widening that holds 95 % of the truths: 18 hold (0.49 se), two miss by 3.92
        # and 5.88 se; the 95th percentile is the 19th of 20 (3.92 / 1.96), not the largest.
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            (folder / "truth").mkdir()
            for k in range(20):
                case = f"drag-{k}"
                t = truth(case, [DRAG])
                if k < 2:  # the friction measured high beside the data: drawn before the fit
                    t["measured"]["particles.friction_particle"] = 0.45
                (folder / "truth" / f"{case}.json").write_text(json.dumps(t))
                (folder / case).mkdir()
                value = {0: 2.6, 1: 2.4}.get(k, 2.95)
                effect = added("linear_drag", DRAG["key"], value, value - 0.2, value + 0.2)
                s = summary([effect], "effect found")
                if k < 2:  # the ones read small have the friction read high: a trade-off
                    s["after"]["params"]["particles.friction_particle"] = 0.50
                (folder / case / "summary.json").write_text(json.dumps(s))
            # Rolling resistance, neutral 0.001, planted 0.002: read 0.0015 (half the departure), its interval
            # ending at the truth (held; 1.96 se from the size).
            (folder / "truth" / "roll.json").write_text(json.dumps(truth("roll", [ROLL])))
            (folder / "roll").mkdir()
            roll = added("rolling_resistance", ROLL["key"], 0.0015, 0.0012, 0.002, neutral=0.001)
            (folder / "roll" / "summary.json").write_text(json.dumps(summary([roll], "effect found")))
            code, out, _ = run("interval_coverage.py", folder)
            self.assertIn("| particles.drag_per_s | 20 | 18 (90 %; 68-99 %) | 2 / 0 | 0.49 | 2.0 |", out)
            # Shares 0.87, 0.80 and 18 x 0.98: the median 0.98 (their mean 0.97).
            # The two read small were measured high too (+0.05): the size against the measurement's error.
            self.assertIn("| particles.drag_per_s | 20 | 0.98 | +0.020 | -0.97 | -0.020 | -0.97 |", out)
            self.assertIn("| particles.rolling_resistance | 1 | 1 (100 %; 3-100 %) | 0 / 0 | 1.96 | - |", out)
            self.assertIn("| particles.rolling_resistance | 1 | 0.50 | +0.020 | - | -0.020 | - |", out)
            self.assertIn("left out: planted values at neutral (no share): 0", out)

    def test_interval_coverage_says_where_the_truths_free_parameter_lay_against_the_final_window(self):
        # The grid 0.1-0.5 in steps of 0.05 (nine nodes): a friction fitted at 0.42 has the window
        # 0.30-0.50 (nearest node 0.40), which holds the truth 0.40; one fitted at 0.20 has 0.10-0.30,
        # which does not. Without a design file nothing can be said ("0 of 0").
        code, out, _ = run("interval_coverage.py", self.pass_dir)
        self.assertIn("| all | 0 of 0 | 0 of 0 |", out)
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            (folder / "design.toml").write_text('[[free]]\nkey = "particles.friction_particle"\nlo = 0.1\nhi = 0.5\nstep = 0.05\n')
            (folder / "design").write_text(str(folder / "design.toml") + "\n")
            (folder / "truth").mkdir()
            for case, fitted, value in (("near", 0.42, 2.95), ("far", 0.20, 2.4), ("far-held", 0.20, 2.95)):
                (folder / "truth" / f"{case}.json").write_text(json.dumps(truth(case, [DRAG])))
                (folder / case).mkdir()
                s = summary([added("linear_drag", DRAG["key"], value, value - 0.2, value + 0.2)], "effect found")
                s["after"]["params"]["particles.friction_particle"] = fitted
                (folder / case / "summary.json").write_text(json.dumps(s))
            code, out, _ = run("interval_coverage.py", folder)
            self.assertEqual(code, 0)
            self.assertIn("| particles.drag_per_s | 1 of 2 | 1 of 1 |", out)
            # The design file as the passes write it: relative to the repository's root (design v2's grid is
            # the same), whatever the working directory.
            (folder / "design").write_text("data/blind/design_v2.toml\n")
            code, out, _ = run("interval_coverage.py", folder, cwd="/")
            self.assertIn("| particles.drag_per_s | 1 of 2 | 1 of 1 |", out)
            # A window recorded in summary.json (after.surface_window) is taken as it is: "near" recorded as
            # 0.10-0.30 has its truth 0.40 outside, "far" recorded as 0.20-0.40 inside.
            for case, window in (("near", [0.10, 0.30]), ("far", [0.20, 0.40])):
                s = json.loads((folder / case / "summary.json").read_text())
                s["after"]["surface_window"] = {"particles.friction_particle": window}
                (folder / case / "summary.json").write_text(json.dumps(s))
            code, out, _ = run("interval_coverage.py", folder)
            self.assertIn("| particles.drag_per_s | 2 of 2 | 0 of 1 |", out)

    def test_surface_optimism_sets_the_fresh_chi2_against_the_surfaces(self):
        # Two calibrations: final surface chi2 43 (the fixture's), fresh 50 and 60: differences +7 and +17, median
        # +12; 44 points, one measurement, dof 43: k = 2, 2k = 4; no model share given: nothing more expected.
        # The baselines were not re-scored.
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            for case, fresh in (("a", 50.0), ("b", 60.0)):
                (folder / case).mkdir()
                s = summary([], "effect found")
                s["after"]["fitted"].update({"n": 44, "dof": 43})
                s["after"]["fitted_fresh"] = {"chi2": fresh}
                (folder / case / "summary.json").write_text(json.dumps(s))
            code, out, _ = run("surface_optimism.py", folder)
            self.assertEqual(code, 0)
            self.assertIn("baseline: none re-scored", out)
            self.assertIn("final: fresh less surface chi2 median +12.0 (quartiles +4.5, +19.5; 2 calibrations), "
                          "expected about +4.0", out)
            self.assertNotIn("held-out point", out)  # none re-scored there
            # With the held-out points: surface 12.0 over 4 points (the fixture's n), fresh 14.0 and 16.0: +0.5 and +1.0.
            for case, fresh in (("a", 14.0), ("b", 16.0)):
                s = json.loads((folder / case / "summary.json").read_text())
                s["after"]["held_out"] = {"chi2": 12.0, "n": 4}
                s["after"]["held_out_fresh"] = {"chi2": fresh}
                (folder / case / "summary.json").write_text(json.dumps(s))
            code, out, _ = run("surface_optimism.py", folder)
            self.assertIn("expected about +4.0; per held-out point median +0.75", out)
            # The model the whole variance, from 6 replicates: E[nu / chi2_nu] = nu / (nu - 2) = 5/3, so 44 points
            # expect 44 x 2/3 = 29.3 more.
            for case in ("a", "b"):
                s = json.loads((folder / case / "summary.json").read_text())
                s.update({"model_noise_share": 1.0, "model_replicates": 6})
                (folder / case / "summary.json").write_text(json.dumps(s))
            code, out, _ = run("surface_optimism.py", folder)
            self.assertIn("expected about +33.3; per held-out point", out)
            # --cases: only b (fresh 60 against 43: +17); a name the folder lacks is refused.
            code, out, _ = run("surface_optimism.py", "--cases", "b", folder)
            self.assertEqual(code, 0)
            self.assertIn("final: fresh less surface chi2 median +17.0", out)
            self.assertIn("1 calibrations", out)
            self.assertEqual(run("surface_optimism.py", "--cases", "b c", folder)[0], 2)
        self.assertEqual(run("surface_optimism.py")[0], 2)

    def test_pass_counts_gives_the_cost_and_the_wording_of_the_identifications(self):
        code, out, _ = run("pass_counts.py", self.pass_dir)
        self.assertEqual(code, 0)
        # drag-low, rolling-high and null-1 added an effect, 1000 runs simulated each (every twin 1000).
        self.assertIn("6 calibrations, 3 added an effect", out)
        self.assertIn("median 1000 (1000-1000); over every calibration 6000", out)
        # drag-low says plain "effect found", rolling-high the form check's flag; no rule 5 asked.
        self.assertIn('single planted effects identified: 2; with an alternative named (rule 5): 0; '
                      'with a plain "effect found": 1', out)
        self.assertNotIn("process CPU", out)  # summaries without cpu_seconds
        self.assertEqual(run("pass_counts.py", self.pass_dir / "nothing")[0], 2)
        # The medians are over the calibrations that added an effect, the sums over every one.
        with tempfile.TemporaryDirectory() as tmp:
            fields = ["case", "truth", "added", "identified", "verdict", "alternatives", "runs_simulated",
                      "process_cpu_s", "wall_s"]
            rows = [["a", "linear_drag", "x=1", "True", "effect found", "none", 100, 10, 5],
                    ["b", "linear_drag", "x=2", "True", "effect found", "none", 300, 30, 7],
                    ["c", "none", "", "", "consistent with noise", "none", 5000, 500, 9]]
            with open(Path(tmp) / "cases.csv", "w", newline="") as f:
                csv.writer(f).writerows([fields] + rows)
            code, out, _ = run("pass_counts.py", tmp)
            self.assertIn("3 calibrations, 2 added an effect", out)
            self.assertIn("median 200 (100-300); over every calibration 5400", out)
            self.assertIn("process CPU: 540 s over every calibration; median per calibration with an effect 20 s", out)
            self.assertIn("wall: 21 s over every calibration; median per calibration with an effect 6 s", out)

    def test_pass_counts_names_a_planted_effect_rule_5_left_open_beside_the_identified(self):
        with tempfile.TemporaryDirectory() as tmp:
            fields = ["case", "truth", "added", "identified", "verdict", "alternatives", "runs_simulated"]
            found = "effect found; these data do not exclude another effect in its place"
            rows = [["a", "linear_drag", "x=1", "True", "effect found", "none", 100],
                    ["b", "rolling_resistance", "x=2", "False", found, "spinning_friction,rolling_resistance", 100],
                    ["c", "rolling_resistance", "x=2", "False", found, "linear_drag", 100],   # the truth not named
                    ["d", "size_scatter", "", "", "consistent with noise", "none", 100]]
            path = Path(tmp) / "cases.csv"
            with open(path, "w", newline="") as f:
                csv.writer(f).writerows([fields] + rows)
            code, out, _ = run("pass_counts.py", tmp)
            self.assertEqual(code, 0)
            self.assertIn("not identified, the planted effect named as an alternative the data do not exclude "
                          "(rule 5): 1 (b); identified or so named: 2 of 4", out)
            with open(path, "w", newline="") as f:   # a pass before rule 5: no such line, rather than a 0
                csv.writer(f).writerows([fields[:5] + fields[6:]] + [r[:5] + r[6:] for r in rows])
            code, out, err = run("pass_counts.py", tmp)
            self.assertEqual(code, 0, err)
            self.assertIn("single planted effects identified: 1", out)
            self.assertNotIn("identified or so named", out)

    def test_decisive_rounds_finds_the_stopped_round_once(self):
        # Once: the replay of spin-high beside the pass is not counted.
        code, out, _ = run("decisive_rounds.py", "1e-3", self.pass_dir)
        self.assertEqual(code, 0)
        self.assertIn("spin-high: chi2 p 0.31, spinning_friction adjusted p 0.0002 < 0.001", out)
        self.assertIn("1 round(s) the option would try; smallest best adjusted p in a stopped round: 0.0002", out)
        code, out, _ = run("decisive_rounds.py", "1e-4", self.pass_dir)
        self.assertIn("0 round(s) the option would try", out)

    def test_wrong_direction_rounds_lists_the_impossible_size(self):
        code, out, _ = run("wrong_direction_rounds.py", self.pass_dir)
        self.assertEqual(code, 0)
        self.assertIn("null-1", out)
        self.assertIn("spinning_friction", out)
        self.assertIn("1 round(s)", out)

    def test_oracle_scale_sets_lambda_against_the_loops_excess(self):
        # Baseline excess chi2 - 43: null-1 +2; drag-low +172 for lambda 170; rolling-high +52 for lambda 50;
        # spin-high +22 for lambda 20.
        remade = Path(self.tmp.name) / "remade"
        (remade / "truth").mkdir(parents=True, exist_ok=True)
        (remade / "truth" / "spin-high.json").write_text(json.dumps(truth("spin-high", [SPIN], power=0.5, chi2=10.0)))
        code, out, err = run("oracle_scale.py", self.pass_dir, "--new", remade)
        self.assertEqual(code, 0, err)
        own, new = out.split("the same twins")[:2]
        self.assertIn("without a planted effect (1): mean excess 2.0", own)
        # (172 - 2) / 170, (52 - 2) / 50 and (22 - 2) / 20, each 1.00, with the pass's lambda ...
        self.assertIn("lambda >= 10 (3 twins): (excess - nulls' mean) / lambda, summed 1.00, median per twin 1.00", own)
        self.assertIn("identified 2 of 4; visible (oracle power >= 0.8) 3 of 4 (the ceiling); identified among the "
                      "visible 2 of 3", own)
        # ... and spin-high's remade lambda 10 gives (22 - 2) / 10 = 2.00; it is no longer visible.
        self.assertIn("lambda >= 10 (1 twins): (excess - nulls' mean) / lambda, summed 2.00", new)
        self.assertIn("visible (oracle power >= 0.8) 0 of 1 (the ceiling)", new)
        self.assertIn("spin-high: 20.0 (0.90) -> 10.0 (0.50); excess 22.0", out)
        code, out, _ = run("oracle_scale.py", self.pass_dir, "--remade", "../remade")
        self.assertIn("visible (oracle power >= 0.8) 2 of 4 (the ceiling)", out.split("where remade")[1])

    def test_missing_folder_is_exit_2(self):
        empty = Path(self.tmp.name) / "empty"
        empty.mkdir(exist_ok=True)
        self.assertEqual(run("visibility_ceiling.py", empty)[0], 2)
        self.assertEqual(run("decisive_rounds.py", "1e-4", empty)[0], 2)
        self.assertEqual(run("oracle_scale.py", empty)[0], 2)



class PairedShift(unittest.TestCase):
    """studies/effects/paired_shift.py: an effect's paired shift of ln J_mid and its dependence on a free parameter."""

    NOISE = [0.01, -0.01, 0.02, -0.02]  # each replicate's own departure of the moved runs (times f)
    NEUTRAL = [0.004, 0.0, -0.004, 0.008]  # ... and of the neutral runs at f 0.3 (shared by shift and slope)

    def ln_j(self, f, s, r):
        """ln J = 3 + r/10 - f - 0.2 s (1 + f), plus the replicates' departures: the shift -0.2 s (1 + f)."""
        return (3 + r / 10 - f - 0.2 * s * (1 + f) + (self.NOISE[r] * f * s)
                + (self.NEUTRAL[r] if s == 0 and f == 0.3 else 0))

    def store(self, path, model="2d", extra_model=None):
        db = sqlite3.connect(path)
        db.execute("create table runs (series text, axes_json text, replicate integer, j_mid real, n_clogs integer, "
                   "model text)")
        for f in (0.3, 0.5):
            for s in (0.0, 0.5, 1.0):
                for r in range(4):
                    db.execute("insert into runs values (?, ?, ?, ?, ?, ?)",
                               ("W/d 4.5", json.dumps({"f": f, "s": s}), r, math.exp(self.ln_j(f, s, r)),
                                int(r == 0 and s == 0), model))
        if extra_model:
            db.execute("insert into runs values ('W/d 4.5', '{\"f\": 0.3, \"s\": 0}', 9, 1.0, 0, ?)", (extra_model,))
        db.commit()
        db.close()

    def run_script(self, path, *keys):
        return subprocess.run([sys.executable, str(STUDIES / "effects" / "paired_shift.py"), str(path), *keys],
                              capture_output=True, text=True)

    def test_the_shift_and_its_change_with_the_free_parameter(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "runs.sqlite"
            self.store(path)
            done = self.run_script(path, "f", "s")
            self.assertEqual(done.returncode, 0, done.stderr)
            self.assertIn("W/d 4.5: 24 runs, 2 with a clog, 0 without J_mid;", done.stdout)
            self.assertIn("| 0.3 | 1 of 4 | 0 of 4 | 0 of 4 |", done.stdout)  # replicate 0 at neutral clogs
            # Each replicate's shifts, recomputed here; the table's cells and the interaction from them.
            shift = {(f, s): [self.ln_j(f, s, r) - self.ln_j(f, 0.0, r) for r in range(4)]
                     for f in (0.3, 0.5) for s in (0.5, 1.0)}
            se = {k: statistics.stdev(v) / 2 for k, v in shift.items()}
            self.assertIn(f"| 0.3 | {statistics.mean(shift[(0.3, 0.5)]):+.4f} ± {se[(0.3, 0.5)]:.4f} | "
                          f"{statistics.mean(shift[(0.3, 1.0)]):+.4f} ± {se[(0.3, 1.0)]:.4f} |", done.stdout)
            self.assertIn("| 0.5 | -0.1500 ± 0.0023 | -0.3000 ± 0.0046 |", done.stdout)
            d = [b - a for a, b in zip(shift[(0.3, 1.0)], shift[(0.5, 1.0)])]
            self.assertIn(f"s 1: shift at f 0.5 less at 0.3: {statistics.mean(d):+.4f} ± {statistics.stdev(d) / 2:.4f}",
                          done.stdout)
            # The largest size as a move of f: its error by the replicates' linearised ratio, which carries the
            # covariance of shift and slope (both subtract the neutral runs at 0.3).
            slope = [(self.ln_j(0.5, 0.0, r) - self.ln_j(0.3, 0.0, r)) / 0.2 for r in range(4)]
            a, b = statistics.mean(shift[(0.3, 1.0)]), statistics.mean(slope)
            linear = [x / b - a * y / b ** 2 for x, y in zip(shift[(0.3, 1.0)], slope)]
            self.assertIn(f"s 1 at f 0.3 acts on ln J_mid as f moved by {a / b:+.3f} ± {statistics.stdev(linear) / 2:.3f}",
                          done.stdout)
            self.assertIn("s 1 at f 0.5 acts on ln J_mid as f moved by", done.stdout)
            # The replicates' own level r/10 is shared by each pair: +1 within the cells.
            self.assertIn("pairs' correlation of ln J_mid within each cell (each size against its neutral): +1.00",
                          done.stdout)
            done = self.run_script(path, "f", "x")
            self.assertEqual(done.returncode, 2)
            self.assertIn("a run without f or x in its axes", done.stderr)
            mixed = Path(tmp) / "mixed.sqlite"
            self.store(mixed, extra_model="3d")
            done = self.run_script(mixed, "f", "s")
            self.assertEqual(done.returncode, 2)
            self.assertIn("holds runs of 2 models (2d, 3d); allowed: one", done.stderr)

    def test_the_pairs_correlation_is_taken_within_each_cell(self):
        # Two cells whose means differ by 10: pooled, the pairs look correlated (+0.98); within each, -1.
        spec = importlib.util.spec_from_file_location("paired_shift", STUDIES / "effects" / "paired_shift.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        cells = [[(0.0, 1.0), (1.0, 0.0)], [(10.0, 11.0), (11.0, 10.0)]]
        self.assertAlmostEqual(module.within_cell_correlation(cells), -1.0)


class CarriedWallTime(unittest.TestCase):
    """studies/blind_pass_wall_time.py on a carry's logs: a launch lost with its machine, one whose
    end is known only by its last save, one stopped, one ended."""

    def test_each_launch_and_the_total(self):
        with tempfile.TemporaryDirectory() as tmp:
            carry = Path(tmp)
            (carry / "launches.txt").write_text(
                "2026-11-28T10:00:00Z launch 1 at 1fbb39b, binary /work/bin-p21/gapflow (a build of d1c04b1, sha256 "
                "a5f046a09623aea5); lost with its machine at the session's end: nothing of it was kept\n"
                "2026-11-28T11:00:00Z launch 2 at 0b2bb3c, binary sha256 31a0d9c685b8258e\n"
                "2026-11-28T13:00:00Z launch 3 at abd, binary b, sha256 0123456789abcdef\n"
                "2026-11-28T13:30:00Z launch 3: stopped by a signal (the pass's command ended with exit 143)\n"
                "2026-11-28T14:00:00Z launch 4 at abd, binary b, sha256 0123456789abcdef\n"
                "2026-11-28T14:10:30Z launch 4: the pass's command ended with exit 0\n"
                "2026-11-28T15:00:00Z launch 5 at abd, binary b, sha256 0123456789abcdef\n")
            (carry / "saves.txt").write_text(
                "2026-11-28T11:05:00Z 1 twins, 0 finished calibrations\n"
                "2026-11-28T12:20:00Z 9 twins, 8 finished calibrations\n"
                "2026-11-28T13:29:00Z 12 twins, 11 finished calibrations\n"
                "2026-11-28T13:40:00Z save failed (exit 2)\n"
                "2026-11-28T15:45:59Z 20 twins, 19 finished calibrations\n")
            done = subprocess.run([sys.executable, str(STUDIES / "blind_pass_wall_time.py"), str(carry)],
                                  capture_output=True, text=True)
            self.assertEqual(done.returncode, 0, done.stderr)
            lines = done.stdout.splitlines()
            self.assertIn("launch 1: from 2026-11-28 10:00:00 UTC, lost with its machine", lines[0])
            self.assertIn("launch 2: from 2026-11-28 11:00:00 to 12:20:00 UTC, 1 h 20 min, until its last save", lines[1])
            self.assertIn("launch 3: from 2026-11-28 13:00:00 to 13:30:00 UTC, 0 h 30 min, stopped", lines[2])
            self.assertIn("launch 4: from 2026-11-28 14:00:00 to 14:10:30 UTC, 0 h 10 min, ended", lines[3])
            self.assertIn("launch 5: from 2026-11-28 15:00:00 to 15:45:59 UTC, 0 h 45 min, until its last save", lines[4])
            # 80 + 30 + 10.5 + 45.98 min = 166.5 min (rounded down once, in the total)
            self.assertIn("wall time over the launches: 2 h 46 min (a launch's end read from its last save); "
                          "1 launch(es) lost", lines[5])

    def test_a_folder_without_launches_is_exit_2(self):
        with tempfile.TemporaryDirectory() as tmp:
            done = subprocess.run([sys.executable, str(STUDIES / "blind_pass_wall_time.py"), tmp],
                                  capture_output=True, text=True)
            self.assertEqual(done.returncode, 2)
            self.assertIn("no launches.txt", done.stderr)


class LawReplayCompare(unittest.TestCase):
    """calibrate/law_replay_compare.py: only the law's fields and the drag's verdict may change."""

    def write(self, folder, case, verdict, effects, extra=None, law=None):
        d = Path(folder) / case
        d.mkdir(parents=True)
        s = {"verdict": verdict, "effects": [{"effect": e} for e in effects], "chi2": 1.0, "run_seconds": 5,
             "form_checks": [{"effect": "linear_drag", "column": "incline_deg", "p_adjusted": 0.5}]}
        if law is not None:
            s.update(law_power=law, law_undetermined=law < 0.8)
            s["form_checks"][0].update(law_spread=0.43, law_power=law)
        s.update(extra or {})
        (d / "summary.json").write_text(json.dumps(s))

    def test_the_law_alone_passes_and_anything_else_is_named(self):
        qualified = "effect found; the drag's law in the speed is not established: a drag of another law may be acting"
        with tempfile.TemporaryDirectory() as tmp:
            before, after = Path(tmp, "b"), Path(tmp, "a")
            self.write(before, "drag", "effect found", ["linear_drag"])
            self.write(after, "drag", qualified, ["linear_drag"], {"run_seconds": 9}, law=0.2)
            self.write(before, "tilt", "effect found", ["lateral_tilt"])
            self.write(after, "tilt", "effect found", ["lateral_tilt"])
            cmd = [sys.executable, str(CALIBRATE / "law_replay_compare.py"), str(before), str(after)]
            done = subprocess.run(cmd, capture_output=True, text=True)
            self.assertEqual(done.returncode, 0, done.stdout + done.stderr)
            self.assertIn("drag: 'effect found' -> '" + qualified + "'; law_power 0.200, undetermined True; "
                          "linear_drag along incline_deg: spread asked 0.430, power 0.200", done.stdout)
            self.assertIn("cases compared: 2; with differences beyond the law: 0", done.stdout)
            # Another field changed, and a verdict changed where no drag was found: both named, exit 1.
            self.write(before, "gap", "effect found", ["gap_offset"])
            self.write(after, "gap", qualified, ["gap_offset"], {"chi2": 2.0})
            done = subprocess.run(cmd, capture_output=True, text=True)
            self.assertEqual(done.returncode, 1, done.stdout)
            self.assertIn("  DIFFERS: chi2", done.stdout)
            self.assertIn("with differences beyond the law: 1 (gap)", done.stdout)
            (after / "gap" / "summary.json").write_text(json.dumps(json.loads((before / "gap" / "summary.json").read_text())
                                                                   | {"verdict": qualified}))
            done = subprocess.run(cmd + ["gap"], capture_output=True, text=True)
            self.assertIn("DIFFERS: the verdict changed where no linear drag was found", done.stdout)
            # A state's surface_window, recorded by later binaries only: left out where one summary lacks it,
            # compared where both have it.
            state = {"params": {"particles.friction_particle": 0.3}}
            window = {"surface_window": {"particles.friction_particle": [0.2, 0.4]}}
            self.write(before, "window", "effect found", ["lateral_tilt"], {"after": state})
            self.write(after, "window", "effect found", ["lateral_tilt"], {"after": state | window})
            done = subprocess.run(cmd + ["window"], capture_output=True, text=True)
            self.assertEqual(done.returncode, 0, done.stdout)
            moved = {"surface_window": {"particles.friction_particle": [0.25, 0.45]}}
            (before / "window" / "summary.json").unlink(), (before / "window").rmdir()
            self.write(before, "window", "effect found", ["lateral_tilt"], {"after": state | moved})
            done = subprocess.run(cmd + ["window"], capture_output=True, text=True)
            self.assertEqual(done.returncode, 1, done.stdout)
            self.assertIn("  DIFFERS: after", done.stdout)
            self.assertEqual(subprocess.run(cmd + ["nothing"], capture_output=True, text=True).returncode, 2)


class FreshPoints(unittest.TestCase):
    """calibrate/fresh_points.py: the fresh seeds' chi^2 gap over the surface's, split per point."""

    HEADER = ("W_over_d,observable,held_out,value,se,before,before_se,after,after_se,residual_before,residual_after,"
              "before_fresh,before_fresh_se,after_fresh,after_fresh_se\n")

    def test_splits_the_gap_into_variances_disagreement_and_cross_term(self):
        # Worked by hand, both states alike. Fitted: an exit offset (linear) with data 1 +- 0.1, surface 0.9 +- 0.1,
        # fresh 1.1 +- 0.1: v = 0.02 on both, d = 0.2, y - s = 0.1: variances 0 (expected 0), disagreement 2
        # (expected 1), cross -2 (expected -1), gap 0; and J_mid (log scale) 10 +- 1 everywhere: all 0, expected 0,
        # 1 and -1. Held out: an exit offset 1 +- 0.1, surface 1 +- 0.1, fresh 1.2 +- 0.2: v_s 0.02, v_f 0.05,
        # variances 0 (expected 0.02/0.05 - 1 = -0.6), disagreement 0.8 (expected 1), cross 0 (expected -0.4),
        # gap 0.8, se ratio 0.5. The fitted chi^2: 0.5 + 0 on both, plus the friction's measurement (0.30 for
        # 0.32 +- 0.04: 0.25).
        with tempfile.TemporaryDirectory() as tmp:
            case = Path(tmp, "one")
            case.mkdir()
            rows = ["4,exit_offset,0,1,0.1,0.9,0.1,0.9,0.1,0,0,1.1,0.1,1.1,0.1",
                    "4,j_mid,0,10,1,10,1,10,1,0,0,10,1,10,1",
                    "5,exit_offset,1,1,0.1,1,0.1,1,0.1,0,0,1.2,0.2,1.2,0.2"]
            (case / "points.csv").write_text(self.HEADER + "\n".join(rows) + "\n")
            state = {"params": {"particles.friction_particle": 0.30}, "fitted": {"chi2": 0.75}, "fitted_fresh": {"chi2": 0.75}}
            summary = {"before": state, "after": state,
                       "measured_free": [{"key": "particles.friction_particle", "measured": 0.32, "se": 0.04}]}
            (case / "summary.json").write_text(json.dumps(summary))
            code, out, err = run("fresh_points.py", tmp)
            self.assertEqual(code, 0, err)
            self.assertIn("1 calibrations with fresh values per point", out)
            self.assertIn("largest difference: surface 0.000, fresh 0.000", out)
            self.assertIn("| final | fitted | 2 | +0.000 | +0.000 (+0.000) | +1.000 (+1.000) | -1.000 (-1.000) | +0.000 | +0.000 | 1.000 |", out)
            self.assertIn("| final | held-out | 1 | +0.800 | +0.000 (-0.600) | +0.800 (+1.000) | +0.000 (-0.400) | -0.200 | +0.400 | 0.500 |", out)
            self.assertIn("| baseline | fitted | 2 | +0.000 | +0.000 (+0.000) | +1.000 (+1.000) | -1.000 (-1.000) |", out)
            self.assertIn("| final | held-out | none added | 1 | +0.800 |", out)   # the summary has no effects
            self.assertNotIn("an effect added", out)
            self.assertIn("| final | j_mid | 1 | +0.000 | +0.000 (+0.000) | +0.000 (+1.000) | +0.000 (-1.000) |", out)
            # A summary whose fitted chi^2 the points do not give is seen by the check.
            summary["after"] = state | {"fitted_fresh": {"chi2": 1.75}}
            (case / "summary.json").write_text(json.dumps(summary))
            self.assertIn("surface 0.000, fresh 1.000", run("fresh_points.py", tmp)[1])
            # points.csv without the fresh columns (binaries before a2dddfa): nothing to read.
            (case / "points.csv").write_text("observable,held_out,value,se,after,after_se\nexit_offset,0,1,0.1,1,0.1\n")
            self.assertIn("0 calibrations with fresh values per point", run("fresh_points.py", tmp)[1])
        self.assertEqual(run("fresh_points.py", "/nonexistent")[0], 2)
        self.assertEqual(run("fresh_points.py")[0], 2)

    def test_reads_only_the_cases_named(self):
        # Two calibrations, one whose fresh runs disagree with its surface by 2 se_f (disagreement 2 per point)
        # and one where they agree (0): --cases keeps the one named; a name the folder lacks is refused.
        with tempfile.TemporaryDirectory() as tmp:
            for name, fresh in (("far", "1.2"), ("near", "1.0")):
                case = Path(tmp, name)
                case.mkdir()
                row = f"4,exit_offset,0,1,0.1,1,0.1,1,0.1,0,0,{fresh},0.1,{fresh},0.1"
                (case / "points.csv").write_text(self.HEADER + row + "\n")
                chi2 = {"chi2": (1 - float(fresh)) ** 2 / 0.02}
                state = {"params": {}, "fitted": {"chi2": 0.0}, "fitted_fresh": chi2}
                (case / "summary.json").write_text(json.dumps({"before": state, "after": state}))
            code, out, err = run("fresh_points.py", "--cases", "far", tmp)
            self.assertEqual(code, 0, err)
            self.assertIn("1 calibrations with fresh values per point (of the 1 cases asked)", out)
            self.assertIn("largest difference: surface 0.000, fresh 0.000", out)
            self.assertIn("| final | fitted | 1 | +2.000 | +0.000 (+0.000) | +2.000 (+1.000) |", out)
            code, out, _ = run("fresh_points.py", tmp)
            self.assertIn("2 calibrations with fresh values per point", out)
            self.assertIn("| final | fitted | 2 | +1.000 | +0.000 (+0.000) | +1.000 (+1.000) |", out)
            code, _, err = run("fresh_points.py", "--cases", "far elsewhere", tmp)
            self.assertEqual(code, 2)
            self.assertIn("no calibration elsewhere", err)
            self.assertEqual(run("fresh_points.py", "--cases", "", tmp)[0], 2)


class FormCheckSignal(unittest.TestCase):
    """calibrate/form_check_signal.py: the false alarms of twins whose planted effects were tried, by lambda."""

    def test_counts_the_flags_below_and_above_the_median_signal(self):
        with tempfile.TemporaryDirectory() as tmp:
            replay = Path(tmp, "pass", "replay-formcheck")
            replay.mkdir(parents=True)
            twins = [("a", 10, 0.9, "True"), ("b", 20, 0.5, "True"), ("c", 2000, 0.01, "True"),
                     ("d", 3000, 0.03, "True"), ("e", 2500, 0.001, "False")]  # e: another effect tried, left out
            with open(replay / "cases.csv", "w", newline="") as f:
                w = csv.writer(f)
                w.writerow(["case", "tried_planted", "signal_chi2"])
                for case, lam, p, tried in twins:
                    w.writerow([case, tried, lam])
                    (replay / case).mkdir()
                    checks = [{"p_adjusted": p, "column": "observable", "statistic": 9.0, "dof": 3},
                              {"p_adjusted": 1.0, "column": "W_over_d", "statistic": 0.1, "dof": 2}]
                    (replay / case / "summary.json").write_text(json.dumps({"form_checks": checks}))
            code, out, err = run("form_check_signal.py", replay)
            self.assertEqual(code, 0, err)
            self.assertIn("| pass | c | 2000 | 0.01 | observable | 9.0 / 3 | yes |", out)
            self.assertNotIn("| e |", out)
            self.assertIn("twins: 4; flagged: 2; median lambda 1010", out)
            self.assertIn("lambda <= median: 0 of 2 flagged; above: 2 of 2", out)
            self.assertIn("flags whose smallest check splits by observable: 2 of 2", out)
            self.assertIn("Mann-Whitney, flagged twins' lambda larger: U = 4, one-sided p = 0.167", out)

class AlternativesReplayCompare(unittest.TestCase):
    """calibrate/alternatives_replay_compare.py: rule 5 may add fits and alternatives and qualify the verdict."""

    QUALIFIED = "effect found; these data do not exclude another effect in its place"

    def write(self, folder, case, verdict, effect, alternatives=None, fits=(), extra=None):
        d = Path(folder) / case
        d.mkdir(parents=True)
        e = {"effect": effect, "value": 0.08}
        if alternatives and not fits:  # the fits that bear the alternatives out: the tried one's, then theirs
            fits = [{"effect": effect, "fitted_p": 0.5}] + [{"effect": a, "fitted_p": 0.3} for a in alternatives]
        rd = {"best": effect, "decision": "added", "fits": list(fits)}
        if alternatives is not None:
            e["alternatives"] = alternatives
            rd["alternatives"] = alternatives
        s = {"verdict": verdict, "effects": [e], "rounds": [rd], "chi2": 1.0, "run_seconds": 5}
        if alternatives is not None:
            s["alternatives"] = 2
        s.update(extra or {})
        (d / "summary.json").write_text(json.dumps(s))

    def test_rule_5_alone_passes_and_anything_else_is_named(self):
        fits = [{"effect": "size_scatter", "fitted_p": 0.6}, {"effect": "rolling_resistance", "fitted_p": 0.3}]
        with tempfile.TemporaryDirectory() as tmp:
            before, after = Path(tmp, "b"), Path(tmp, "a")
            self.write(before, "q4", "effect found", "size_scatter")
            self.write(after, "q4", self.QUALIFIED, "size_scatter", ["rolling_resistance"], fits,
                       {"run_seconds": 9, "cpu_seconds": 7})  # a binary that measures its CPU: a run field
            self.write(before, "tilt", "effect found", "lateral_tilt")
            self.write(after, "tilt", "effect found", "lateral_tilt", [])
            cmd = [sys.executable, str(CALIBRATE / "alternatives_replay_compare.py"), str(before), str(after)]
            done = subprocess.run(cmd, capture_output=True, text=True)
            self.assertEqual(done.returncode, 0, done.stdout + done.stderr)
            self.assertIn("q4: 'effect found' -> '" + self.QUALIFIED + "'; size_scatter or rolling_resistance; "
                          "fits: size_scatter p 0.6, rolling_resistance p 0.3", done.stdout)
            self.assertIn("cases compared: 2; with differences beyond rule 5: 0", done.stdout)
            # A size that moved, a name without the qualifier, a qualifier without a name: each named, exit 1.
            self.write(before, "drag", "effect found", "linear_drag")
            self.write(after, "drag", "effect found", "linear_drag", [], extra={"chi2": 2.0})
            self.write(before, "gap", "effect found", "gap_offset")
            self.write(after, "gap", "effect found", "gap_offset", ["corner_rounding"])
            self.write(before, "spin", "effect found", "spinning_friction")
            self.write(after, "spin", self.QUALIFIED, "spinning_friction", [])
            done = subprocess.run(cmd, capture_output=True, text=True)
            self.assertEqual(done.returncode, 1, done.stdout)
            self.assertIn("  DIFFERS: chi2", done.stdout)
            self.assertIn("with differences beyond rule 5: 3 (drag, gap, spin)", done.stdout)
            # A poor fit is not qualified by rule 5.
            self.write(before, "roll", "effect found, poor fit remains", "rolling_resistance")
            self.write(after, "roll", self.QUALIFIED, "rolling_resistance", ["linear_drag"])
            done = subprocess.run(cmd + ["roll"], capture_output=True, text=True)
            self.assertIn("DIFFERS: the verdict changed otherwise than rule 5 allows", done.stdout)
            self.assertEqual(subprocess.run(cmd + ["nothing"], capture_output=True, text=True).returncode, 2)
            # The drag's law reservation is kept after the rule's; replaced by it only with --pass23-wording (that
            # replay's binary); never gained, and never left without the rule's where an alternative is named.
            law = "; the drag's law in the speed is not established: a drag of another law may be acting"
            for case, was, now in (("both", "effect found" + law, self.QUALIFIED + law),
                                   ("old", "effect found" + law, self.QUALIFIED),
                                   ("gained", "effect found", self.QUALIFIED + law),
                                   ("unqualified", "effect found" + law, "effect found" + law)):
                self.write(before, case, was, "linear_drag")
                self.write(after, case, now, "linear_drag", ["rolling_contact"])
            cases = ["both", "old", "gained", "unqualified"]
            done = subprocess.run(cmd + cases, capture_output=True, text=True)
            self.assertIn("with differences beyond rule 5: 3 (old, gained, unqualified)", done.stdout)
            done = subprocess.run(cmd[:2] + ["--pass23-wording"] + cmd[2:] + cases, capture_output=True, text=True)
            self.assertIn("with differences beyond rule 5: 3 (both, gained, unqualified)", done.stdout)
            # What rule 5 wrote must be what its fits give, and the fits rule 4 made must stay.
            rule4 = [{"effect": "rolling_contact", "bic": -10.0}]
            self.write(before, "r4", "effect found", "rolling_contact", fits=rule4)
            self.write(after, "r4", "effect found", "rolling_contact", [], [{"effect": "rolling_contact", "bic": -9.0}])
            self.write(before, "low", "effect found", "restitution")
            self.write(after, "low", self.QUALIFIED, "restitution", ["size_scatter"],
                       [{"effect": "restitution", "fitted_p": 0.5}, {"effect": "size_scatter", "fitted_p": 0.01}])
            self.write(before, "nan", "effect found", "corner_rounding")
            self.write(after, "nan", "effect found", "corner_rounding", [],
                       [{"effect": "corner_rounding", "fitted_p": 0.5}, {"effect": "gap_offset", "fitted_p": None}])
            done = subprocess.run(cmd + ["r4", "low", "nan"], capture_output=True, text=True)
            self.assertIn("DIFFERS: round 1: the fits rule 4 made changed", done.stdout)
            self.assertIn("DIFFERS: round 1: alternatives ['size_scatter'] where its fits give []", done.stdout)
            self.assertIn("nan: unchanged 'effect found'; none named; fits: corner_rounding p 0.5, gap_offset p -",
                          done.stdout)
            self.assertIn("with differences beyond rule 5: 2 (r4, low)", done.stdout)
            # An added effect's alternatives are its round's less the effects added: a name its round did not give,
            # or one a later round added beside it, is a difference.
            fits = [{"effect": "size_scatter", "fitted_p": 0.6}, {"effect": "rolling_resistance", "fitted_p": 0.3}]
            self.write(before, "eff", "effect found", "size_scatter")
            self.write(after, "eff", self.QUALIFIED, "size_scatter", ["rolling_resistance"], fits)
            s = json.loads((after / "eff" / "summary.json").read_text())
            s["effects"][0]["alternatives"] = ["linear_drag"]
            (after / "eff" / "summary.json").write_text(json.dumps(s))
            two = [{"effect": "size_scatter", "value": 0.08}, {"effect": "rolling_resistance", "value": 0.01}]
            for folder, alternatives in ((before, None), (after, [[], []])):
                d = folder / "pair"
                d.mkdir()
                effects = [dict(e) for e in two]
                rounds = [{"best": "size_scatter", "decision": "added"},
                          {"best": "rolling_resistance", "decision": "added"}]
                if alternatives is not None:  # rule 5 named rolling resistance in round 1; round 2 added it
                    rounds[0] |= {"fits": fits, "alternatives": ["rolling_resistance"]}
                    rounds[1] |= {"fits": [], "alternatives": []}
                    for e, a in zip(effects, alternatives):
                        e["alternatives"] = a
                s = {"verdict": "effect found", "effects": effects, "rounds": rounds, "chi2": 1.0}
                if alternatives is not None:
                    s["alternatives"] = 2
                (d / "summary.json").write_text(json.dumps(s))
            done = subprocess.run(cmd + ["eff", "pair"], capture_output=True, text=True)
            self.assertIn("DIFFERS: size_scatter: alternatives ['linear_drag'] where its round gives "
                          "['rolling_resistance']", done.stdout)
            self.assertIn("with differences beyond rule 5: 1 (eff)", done.stdout)
            s = json.loads((after / "pair" / "summary.json").read_text())
            s["effects"][0]["alternatives"] = ["rolling_resistance"]  # kept though a later round added it
            (after / "pair" / "summary.json").write_text(json.dumps(s))
            done = subprocess.run(cmd + ["pair"], capture_output=True, text=True)
            self.assertIn("DIFFERS: size_scatter: alternatives ['rolling_resistance'] where its round gives []",
                          done.stdout)

    def test_blind_summary_counts_the_found_effects_whose_identity_is_withheld(self):
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            (folder / "truth").mkdir()
            cases = {
                "drag-low": (truth("drag-low", [DRAG], power=1.0, chi2=170.0),
                             [added("linear_drag", DRAG["key"], 2.9, 2.5, 3.2) | {"alternatives": ["spinning_friction"]}],
                             self.QUALIFIED),
                "spin-high": (truth("spin-high", [SPIN], power=1.0, chi2=90.0),
                              [added("spinning_friction", SPIN["key"], 0.7, 0.5, 0.9) | {"alternatives": []}],
                              "effect found"),
                "rolling-high": (truth("rolling-high", [ROLL], power=1.0, chi2=50.0),
                                 [added("linear_drag", DRAG["key"], 1.0, 0.5, 1.5) |
                                  {"alternatives": ["rolling_resistance"]}], self.QUALIFIED),
                "outside-quadratic-4": (truth("outside-quadratic-4", [OUTSIDE], power=0.5, chi2=9.0),
                                        [added("size_scatter", "particles.size_scatter", 0.08, 0.07, 0.09) |
                                         {"alternatives": ["rolling_resistance", "linear_drag"]}], self.QUALIFIED),
            }
            for i, (case, (t, effects, verdict)) in enumerate(cases.items()):
                (folder / "truth" / f"{case}.json").write_text(json.dumps(t))
                (folder / case).mkdir()
                s = summary(effects, verdict) | {"alternatives": 2, "cpu_seconds": 100.0 + 10 * i}
                # Rule 5's fits beside the best score, which is tried: not a rule-4 contest (contenders 1).
                s["rounds"] = [{"best": effects[0]["effect"], "fits": [{"effect": effects[0]["effect"]}],
                                "candidates": [{"effect": "restitution", "visible": True, "score": 20.0}]}]
                (folder / case / "summary.json").write_text(json.dumps(s))
            code, _, err = run("blind_summary.py", folder)
            self.assertEqual(code, 0, err)
            with open(folder / "cases.csv", newline="") as f:
                rows = {r["case"]: r for r in csv.DictReader(f)}
            self.assertEqual(rows["drag-low"]["alternatives"], "spinning_friction")
            self.assertEqual(rows["drag-low"]["contests"], "")
            self.assertEqual(rows["spin-high"]["alternatives"], "none")
            self.assertEqual(rows["drag-low"]["identified"], "True")  # still counted as identified
            report = (folder / "report.md").read_text()
            self.assertIn("planted effects found with alternatives these data do not exclude in their place (rule 5; "
                          "the verdict says so unless a poor fit or held-out points beyond the noise come first; still "
                          "counted as identified): 1 of 2 (50 %) (drag-low: spinning_friction)", report)
            self.assertIn("single planted effects not identified, with alternatives named: rolling-high (linear_drag; "
                          "not excluded: rolling_resistance)", report)
            self.assertIn("size_scatter (not excluded in its place: rolling_resistance,linear_drag)", report)
            # The processes' own CPU beside the runs' summed wall times (600 s each in the fixture).
            self.assertIn("600 CPU-s, about 5.0 min on 2 cores (range 600-600 CPU-s; each run's wall time summed, so "
                          "CPU seconds only where the cores were not shared)", report)
            self.assertIn("* CPU the calibrations' processes used (every thread, the runs they simulated; a store "
                          "shared between twins lowers it): median 115 CPU-s (range 100-130)", report)
            # calibrate/pass_counts.py: of the two identified, drag-low qualified by rule 5, spin-high plain.
            code, out, err = run("pass_counts.py", folder)
            self.assertEqual(code, 0, err)
            self.assertIn('single planted effects identified: 2; with an alternative named (rule 5): 1 (drag-low); '
                          'with a plain "effect found": 1', out)
            self.assertIn("process CPU: 460 s over every calibration; median per calibration with an effect 115 s", out)
            # rolling-high read as linear drag with its planted rolling resistance not excluded: beside, not in.
            self.assertIn("not identified, the planted effect named as an alternative the data do not exclude "
                          "(rule 5): 1 (rolling-high); identified or so named: 3 of 3", out)
            # Summaries made without the option: no such lines, an empty column.
            for case in cases:
                s = json.loads((folder / case / "summary.json").read_text())
                del s["alternatives"]
                (folder / case / "summary.json").write_text(json.dumps(s))
            self.assertEqual(run("blind_summary.py", folder)[0], 0)
            self.assertNotIn("rule 5", (folder / "report.md").read_text())
            self.assertIn("CPU the calibrations' processes used", (folder / "report.md").read_text())


class GridRuns(unittest.TestCase):
    """calibrate/node_correlation_check.py and grid_noise_check.py on a fake pass store with known answers."""

    def make_pass(self, root):
        """One twin, one design point, 5 friction nodes (0.1-0.5 in 0.1) of 5 replicates, and a re-score at 0.25
        on 6 fresh runs. Replicate r at node k: J_mid = exp(1 + 0.1 r + 0.01 k) (the same error at every node:
        correlation +1, and the node means lie on a line: lack of fit 0); the crossings at x = (r - 2)(-1)^k mm
        (the error flips sign from node to node: -1 one step apart, +1 two apart), all at t = 2 s (no spread:
        no first-crossing row). The re-score's J_mid: exp(1 + 0.2 r) for r = 0..5. The twin's seed is 7."""
        (root / "twins").mkdir(parents=True)
        (root / "twins" / "t1.toml").write_text(
            '[model]\nseed = 7\n\n[[free]]\nkey = "particles.friction_particle"\nlo = 0.1\nhi = 0.5\nstep = 0.1\n')
        db = sqlite3.connect(root / "runs.sqlite")
        db.execute("create table runs (job_key text, study text, series text, point integer, replicate integer, "
                   "base_seed integer, j_mid real)")
        db.execute("create table crossings (job_key text, id integer, t_s real, x_m real)")
        def add(key, series, rep, j, xs, seed=7):
            db.execute("insert into runs values (?, 'calibrate:t1', ?, 0, ?, ?, ?)", (key, series, rep, seed, j))
            for n, x in enumerate(xs):
                db.execute("insert into crossings values (?, ?, 2.0, ?)", (key, n, x))
        for k in range(5):
            for r in range(5):
                x = (r - 2) * (-1) ** k * 1e-3
                add(f"g{k}{r}", f"particles.friction_particle={0.1 + 0.1 * k}", r, math.exp(1 + 0.1 * r + 0.01 * k), [x, x])
        for r in range(6):
            add(f"f{r}", "particles.friction_particle=0.25", r, math.exp(1 + 0.2 * r), [])
        # A run on another seed that lands on a grid node: not a grid run (it would break every answer below).
        add("o0", "particles.friction_particle=0.1", 0, 1e6, [0.5], seed=8)
        # A drag moved at the first three nodes (two keys: not grid runs), its shift in ln J_mid 0.05 (r + k) at
        # replicate r, node k: within each node a variance of 0.05^2 var(0..4), pooled over the nodes that plus
        # the nodes' spread.
        for k in range(3):
            for r in range(5):
                add(f"s{k}{r}", f"particles.friction_particle={0.1 + 0.1 * k}, particles.drag_per_s=1", r,
                    math.exp(1 + 0.1 * r + 0.01 * k + 0.05 * (r + k)), [0.0])
        db.commit()
        db.close()

    def test_the_correlation_by_distance_and_the_grids_lack_of_fit(self):
        with tempfile.TemporaryDirectory() as tmp:
            root = Path(tmp, "pass")
            self.make_pass(root)
            code, out, err = run("node_correlation_check.py", root)
            self.assertEqual(code, 0, err)
            rows = {line.split()[0]: line for line in out.splitlines()[2:]}
            self.assertEqual(rows["j_mid"].split()[1::2], ["+1.000", "+1.000", "+1.000", "+1.000"])
            self.assertEqual(rows["exit_offset"].split()[1::2], ["-1.000", "+1.000", "-1.000", "+1.000"])
            self.assertEqual(rows["j_mid"].split()[2], "(20)")  # 5 replicate pairs in each of 4 node pairs 1 apart
            self.assertEqual(rows["front_arrival"].split(), ["front_arrival"])  # no spread
            code, out, err = run("grid_noise_check.py", root)
            self.assertEqual(code, 0, err)
            j_mid = next(line for line in out.splitlines() if line.startswith("j_mid"))
            # One window, its means on a line; then the re-score's per-run variance over the grid's pooled
            # within-node one (5 replicates at 5 nodes), its mean and median over the one re-score.
            ratio = statistics.variance([0.2 * r for r in range(6)]) / statistics.variance([0.1 * r for r in range(5)])
            shifts = [0.05 * (r + k) for k in range(3) for r in range(5)]
            spread = statistics.variance(shifts) / statistics.variance([0.05 * r for r in range(5)])
            self.assertRegex(j_mid, rf"^j_mid\s+0\.000 \(\s*2\)\s+{ratio:.3f}\s+{ratio:.3f} \(1\)\s+{spread:.3f} \(1\)$")
        for script in ("node_correlation_check.py", "grid_noise_check.py"):
            self.assertEqual(run(script, "/nonexistent")[0], 2)
            self.assertEqual(run(script)[0], 2)


class ReplicateTails(unittest.TestCase):
    """calibrate/replicate_tails.py on a fake study store with known moments."""

    def test_an_asymmetric_samples_moments(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp, "runs.sqlite")
            db = sqlite3.connect(path)
            db.execute("create table runs (job_key text, series text, point integer, point_label text, "
                       "replicate integer, j_mid real)")
            db.execute("create table crossings (job_key text, id integer, t_s real, x_m real)")
            # ln J_mid and the exit offset (mm) at 0, 0, 0, 4; every crossing at t = 2 s (no spread: no row).
            for r, v in enumerate((0, 0, 0, 4)):
                db.execute("insert into runs values (?, 's', 0, 'gap=1', ?, ?)", (f"k{r}", r, math.exp(v)))
                db.execute("insert into crossings values (?, 0, 2.0, ?)", (f"k{r}", v * 1e-3))
            db.commit()
            db.close()
            code, out, err = run("replicate_tails.py", path)
            self.assertEqual(code, 0, err)
            rows = [line.split(" | ") for line in out.splitlines()[2:]]
            self.assertEqual([row[2] for row in rows], ["j_mid", "exit_offset"])
            for row in rows:
                # Deviations -1, -1, -1, 3: m2 3, m3 6, m4 21. sd sqrt(12/3) = 2; skew 6/3^1.5; excess kurtosis
                # 21/9 - 3 = -2/3 (a normal sample's se sqrt(24/4)); |z| 3/sqrt(3); 1 + 5 (-2/3)/12 = 0.72
                self.assertEqual(row[3:], ["4", "2.0000", "+1.15", "-0.67 (2.45)", "1.73", "0.72 |"])
        self.assertEqual(run("replicate_tails.py", "/nonexistent")[0], 2)


class TailsChi2(unittest.TestCase):
    """calibrate/tails_chi2.py: the loop's chi^2 and the fresh disagreement on resampled runs, against normal samples."""

    def store(self, tmp, samples):
        path = Path(tmp, "runs.sqlite")
        db = sqlite3.connect(path)
        db.execute("create table runs (job_key text, series text, point integer, point_label text, "
                   "replicate integer, j_mid real)")
        db.execute("create table crossings (job_key text, id integer, t_s real, x_m real)")
        for point, values in enumerate(samples):
            for r, v in enumerate(values):
                db.execute("insert into runs values (?, 's', ?, ?, ?, ?)",
                           (f"k{point}-{r}", point, f"gap={point}", r, math.exp(v)))
        db.commit()
        db.close()
        return path

    def test_a_jammed_mixture_raises_the_disagreement_and_a_normal_sample_does_not(self):
        normal = [statistics.NormalDist().inv_cdf((i + 0.5) / 150) for i in range(150)]
        jammed = [0.1 * x for x in normal[:135]] + [-3.0] * 15     # 10 % of the runs far below (jams)
        with tempfile.TemporaryDirectory() as tmp:
            code, out, err = run("tails_chi2.py", self.store(tmp, [normal, jammed]), "--draws", "2000")
            self.assertEqual(code, 0, err)
            rows = [line.split(" | ") for line in out.splitlines() if line.startswith("| s |")]
            self.assertEqual(len(rows), 2)

            def tails(row, column):   # "mean (normal) +x ± se" -> x
                return float(row[3 + column].split(") ")[1].split(" ± ")[0])
            # Columns: chi2 own, disagreement own, chi2 pooled, disagreement pooled.
            for column in range(4):   # the draws' se about 0.035-0.045: within about 3 of them
                self.assertLess(abs(tails(rows[0], column)), 0.12, rows[0])
            self.assertGreater(tails(rows[1], 1), 0.3, rows[1])
            self.assertGreater(tails(rows[1], 3), 0.3, rows[1])
            # The loop's own chi^2 is not raised by the jams: the surface's 30 runs state a se to match.
            self.assertLess(abs(tails(rows[1], 0)), 0.12, rows[1])
            # The normal reference itself: a point's chi^2 with variances estimated from 10 data runs and 5 nodes
            # of 6 lies above 1 (about 1.10), less with the nodes' variance pooled; the disagreement's about +0.17.
            row = next(line for line in out.splitlines() if line.startswith("| normal samples"))
            normal = [float(c.split(" ± ")[0]) for c in row.strip(" |").split("|")[2:]]
            own, disagreement, pooled = normal[0], normal[1], normal[2]
            self.assertTrue(1.07 < own < 1.14 and 1.05 < pooled < own, normal)
            self.assertTrue(0.12 < disagreement < 0.22, normal)
            self.assertTrue(5.5 < normal[4] < 7.0, normal)   # beyond 3.84: above the 5 % of known variances
        self.assertEqual(run("tails_chi2.py", "/nonexistent")[0], 2)


class NullPValues(unittest.TestCase):
    """calibrate/null_p_values.py: the null twins' p-values and per-observable residuals, counted."""

    def test_counts_the_low_p_values_and_the_mean_squares(self):
        with tempfile.TemporaryDirectory() as tmp:
            (Path(tmp) / "twins").mkdir()
            cases = (("null-1", (0.01, 0.2, 0.3), (3.0, 1.0)), ("null-2", (0.5, 0.4, 0.9), (0.0, -2.0)),
                     ("drag-high", (0.001,) * 3, (9.0, 9.0)))   # not a null: left out
            for case, ps, residuals in cases:
                folder = Path(tmp, case)
                folder.mkdir()
                (Path(tmp) / "twins" / f"{case}.toml").write_text(
                    "[observable]\nfloor_relative = 0.03\n[floors]\nexit_offset = { absolute = 0.1 }\n")
                before = {key: {"n": 2, "p": p} for key, p in zip(("fitted", "held_out_fresh", "fitted_fresh"), ps)}
                (folder / "summary.json").write_text(json.dumps({"before": before}))
                with open(folder / "points.csv", "w", newline="") as f:
                    w = csv.writer(f)
                    w.writerow(["observable", "held_out", "value", "se", "before", "before_se", "residual_before"])
                    # J_mid 10 +- 0.5 (fit scale 0.05: floor 0.03, 0.04 measured), the surface's 0.03 (20 +- 0.6).
                    w.writerow(["j_mid", 0, 10.0, 0.5, 20.0, 0.6, residuals[0]])
                    w.writerow(["exit_offset", 0, 0.0, 0.2, 0.0, 0.1, residuals[1]])   # linear: floor x |0| = 0
                    w.writerow(["exit_offset", 1, 0.0, 0.2, 0.0, 0.1, 50.0])   # held out: not a fitted point
            code, out, err = run("null_p_values.py", tmp)
            self.assertEqual(code, 0, err)
            self.assertIn("2 null calibrations in 1 folders", out)
            # One of 2 below 0.05 (a uniform p: 0.1 expected; at least one: 1 - 0.95^2 = 0.0975); the quartiles
            # of (0.01, 0.5) by linear interpolation; KS: the empirical cdf's largest gap, 1 - 0.5 (exact p 0.5).
            self.assertIn("| fitted (surface) | 2 | 1 (0.1; 0.098) | 1 (0.2; 0.190) | 0.13, 0.26, 0.38 | 0.500 (0.500)",
                          out)
            self.assertIn("| held-out (fresh seeds) | 2 | 0 (0.1; 1.000) | 0 (0.2; 1.000) | 0.25, 0.30, 0.35 |", out)
            self.assertIn("| fitted (fresh seeds) | 2 | 0 (0.1; 1.000) | 0 (0.2; 1.000) | 0.45, 0.60, 0.75 |", out)
            # Part 2: null-1 only (p 0.01), its sums of squares per observable.
            self.assertIn(f"| {Path(tmp).name} | null-1 | 0.010 | 1.0 (1) | 9.0 (1) |", out)
            self.assertNotIn("| null-2 | 0.500", out)
            # j_mid: squares 9 and 0, mean 4.5 (se over the two calibrations 4.5); not floor
            # (0.0016 + 0.0009) / (0.0025 + 0.0009) = 0.735 at both.
            row = next(line for line in out.splitlines() if line.startswith("| j_mid"))
            self.assertTrue(row.startswith("| j_mid | 2 | 4.500 (4.500) | 0.735 | "), row)
            self.assertTrue(row.endswith("| 50.00 % | 0.00 % | 1 |"), row)
            row = next(line for line in out.splitlines() if line.startswith("| exit_offset"))
            # The exit offset's own floor, absolute 0.1 (its relative default would give 0 x |0|): e^2 0.04, 0.01
            # of it floor, the surface's 0.01: (0.03 + 0.01) / (0.04 + 0.01) = 0.8.
            self.assertTrue(row.startswith("| exit_offset | 2 | 2.500 (1.500) | 0.800 | "), row)
        self.assertEqual(run("null_p_values.py")[0], 2)
        with tempfile.TemporaryDirectory() as tmp:
            self.assertEqual(run("null_p_values.py", tmp)[0], 2)


class ControlBaseline(unittest.TestCase):
    """calibrate/control_baseline.py: a pass and its control start from the same baseline, twin by twin."""

    def test_names_a_baseline_that_differs_and_counts_the_sizes_correlation(self):
        def write(folder, case, friction, chi2, effects):
            (folder / case).mkdir(parents=True)
            (folder / case / "summary.json").write_text(json.dumps(
                {"before": {"params": {"particles.friction_particle": friction}, "fitted": {"chi2": chi2}},
                 "effects": effects}))
        with tempfile.TemporaryDirectory() as tmp:
            mine, control = Path(tmp, "pass"), Path(tmp, "control")
            counted = {"effect": "tilt", "size_correlation": 0.6}
            bounded = {"effect": "drag", "size_correlation": None}
            write(mine, "a", 0.3, 40.0, [counted])
            write(control, "a", 0.3 * (1 + 1e-12), 40.0, [])           # within 1e-9: the same
            write(mine, "b", 0.3, 40.0, [bounded, {"effect": "old"}])  # one from a build without the field
            write(control, "b", 0.31, 40.0, [])
            write(mine, "c", 0.3, 40.0, [])                            # not in the control: not compared
            code, out, err = run("control_baseline.py", mine, control)
            self.assertEqual(code, 0, err)
            self.assertIn("b: DIFFERS: particles.friction_particle 0.3 against 0.31", out)
            self.assertNotIn("a: DIFFERS", out)
            self.assertIn("baseline: 1 of 2 calibrations the same", out)
            self.assertIn("the sizes' correlation counted for 1 of 3 added effects (1 from a build without the field)",
                          out)
            self.assertEqual(run("control_baseline.py", mine, Path(tmp, "nothing"))[0], 2)
            empty = Path(tmp, "empty")
            empty.mkdir()
            self.assertEqual(run("control_baseline.py", mine, empty)[0], 2)


class Reservations(unittest.TestCase):
    """calibrate/reservations_check.py: both reservations where both are due."""

    def test_names_a_verdict_that_drops_the_laws_reservation(self):
        law = "the drag's law in the speed is not established: a drag of another law may be acting"
        found = "effect found; these data do not exclude another effect in its place"
        rows = [("a", "linear_drag", "True", f"{found}; {law}"),    # both, as due
                ("b", "rolling_resistance", "True", found),          # the law's missing
                ("c", "none", "True", found),                        # no alternative: not due
                ("d", "linear_drag", "False", found)]                # the law established: not due
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp, "cases.csv")
            with open(path, "w", newline="") as f:
                w = csv.writer(f)
                w.writerow(["case", "alternatives", "law_undetermined", "verdict"])
                w.writerows(rows)
            code, out, err = run("reservations_check.py", path)
            self.assertEqual(code, 0, err)
            self.assertIn("a: both reservations", out)
            self.assertIn("b: LAW RESERVATION MISSING", out)
            self.assertIn("calibrations with both reservations due: 2; missing the law's: 1", out)
        self.assertEqual(run("reservations_check.py", "/nonexistent.csv")[0], 2)
        self.assertEqual(run("reservations_check.py")[0], 2)


if __name__ == "__main__":
    unittest.main()
