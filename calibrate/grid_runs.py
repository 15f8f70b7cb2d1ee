"""A blind pass's run store read per run (the analysis scripts of the grid's noise: node_correlation_check.py,
grid_noise_check.py): each run's observables on the loop's fit scales, the twins with one free parameter, and
the scripts' one argument."""
import math
import sqlite3
import sys
import tomllib
from pathlib import Path

# J_mid, the first crossing's time and the crossings' spread on a log scale, their mean position (the exit
# offset, mm) linear, as the loop's fit scales have them (calibrate/data_file.cpp default_scale).
OBSERVABLES = ("j_mid", "front_arrival", "exit_offset", "exit_spread")

_RUNS = """select r.series, r.point, r.replicate, r.base_seed, r.j_mid,
                  (select min(t_s) from crossings c where c.job_key = r.job_key),
                  (select avg(x_m) from crossings c where c.job_key = r.job_key),
                  (select count(*) from crossings c where c.job_key = r.job_key),
                  (select avg(x_m * x_m) from crossings c where c.job_key = r.job_key)
           from runs r where r.study = ? and r.series like ?"""


def observables(j_mid, first, mean_x, n, mean_x2):
    """{observable: fit-scale value} of one run, leaving out what it does not define."""
    v = {}
    if j_mid and j_mid > 0: v["j_mid"] = math.log(j_mid)
    if first and first > 0: v["front_arrival"] = math.log(first)
    if n and n >= 1: v["exit_offset"] = mean_x * 1e3
    if n and n >= 2:
        var = (mean_x2 - mean_x * mean_x) * n / (n - 1)
        if var > 0: v["exit_spread"] = math.log(math.sqrt(var) * 1e3)
    return v


def runs(db, study, key):
    """[(series' keys and values, point, replicate, seed, {observable: value})] of one twin's runs whose series
    starts with `key`= (the grid's and re-scores' one key; an effect moved beside it, two)."""
    out = []
    for series, point, rep, seed, *measured in db.execute(_RUNS, (f"calibrate:{study}", f"{key}=%")):
        parts = [(k, float(v)) for k, v in (p.split("=", 1) for p in series.split(", "))]
        out.append((parts, point, rep, seed, observables(*measured)))
    return out


def one_parameter_twins(pass_dir):
    """(twin name, free key, lo, step, the data file's seed) of each twin with one free parameter."""
    for twin in sorted((pass_dir / "twins").glob("*.toml")):
        spec = tomllib.loads(twin.read_text())
        if len(spec["free"]) == 1:
            f = spec["free"][0]
            yield twin.stem, f["key"], f["lo"], f["step"], spec["model"]["seed"]


def open_pass(doc):
    """The pass folder the command line names, and its store read-only; usage or a folder that is not a pass
    with its store: exit 2."""
    if len(sys.argv) != 2:
        print(doc, file=sys.stderr)
        sys.exit(2)
    folder = Path(sys.argv[1])
    if not (folder / "runs.sqlite").is_file() or not (folder / "twins").is_dir():
        print(f"error: {folder} is not a blind pass with its store (runs.sqlite and twins/ expected)", file=sys.stderr)
        sys.exit(2)
    return folder, sqlite3.connect(f"file:{folder / 'runs.sqlite'}?mode=ro", uri=True)


def grid_level(value, lo, step):
    """The grid level of a parameter value, or None off the grid (a fit's re-score)."""
    level = (value - lo) / step
    return round(level) if abs(level - round(level)) < 1e-6 else None
