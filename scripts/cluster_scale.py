#!/usr/bin/env python3
"""Cost per run of each committed study and what three workloads would take on 2, 64 and 1000 cores.

    scripts/cluster_scale.py RESULTS OUT_DIR > OUT_DIR/scale.md     (scripts/cluster_scale.sh runs it)

Costs are measured: wall_time_s of every run in RESULTS/*/runs.sqlite (one core per run, 2 shared
cores at load ~5-7, so a cluster core is likely faster). Merge rate and per-job plan time come from
OUT_DIR/merge_10k.txt and OUT_DIR/plan_time.txt. Projections: T(C) = max(cost / C, longest run) +
the share's plan expansion + the merge; a lower bound for a perfectly balanced share of whole runs.
"""
import glob
import os
import sqlite3
import statistics
import sys

results, out = sys.argv[1], sys.argv[2]


def key_values(path):
    values = {}
    for line in open(path):
        if '=' in line and not line.startswith('#'):
            k, v = line.strip().split('=', 1)
            values[k] = float(v)
    return values


merge = key_values(os.path.join(out, 'merge_10k.txt'))
plan = key_values(os.path.join(out, 'plan_time.txt'))

studies = {}
print('Cost per run of the committed studies (`wall_time_s` in `results/*/runs.sqlite`; one core per run):\n')
print('| study | model | runs | mean s/run | median | longest | core-hours |')
print('|---|---|---:|---:|---:|---:|---:|')
for f in sorted(glob.glob(os.path.join(results, '*', 'runs.sqlite'))):
    name = os.path.basename(os.path.dirname(f))
    db = sqlite3.connect(f'file:{f}?mode=ro', uri=True)
    for model in ('2d', '3d'):
        w = [r[0] for r in db.execute('select wall_time_s from runs where model = ?', (model,))]
        if not w:
            continue
        points = db.execute("select count(distinct series || '/' || point) from runs where model = ?", (model,)).fetchone()[0]
        studies[(name, model)] = dict(mean=statistics.mean(w), longest=max(w), points=points)
        print(f'| {name} | {model} | {len(w)} | {statistics.mean(w):.1f} | {statistics.median(w):.1f} | {max(w):.0f} | {sum(w) / 3600:.2f} |')

d2, d3 = studies[('flow-vs-distance', '2d')], studies[('flow-vs-distance', '3d')]
g2 = studies[('flow-vs-gap', '2d')]
points = d2['points']
longest = max(d2['longest'], d3['longest'])
paper_runs = points * 20 * 2
paper_cost = points * 20 * (d2['mean'] + d3['mean'])
calib_iters, calib_points, calib_reps = 40, g2['points'], 5
workloads = [
    (f'paper-scale obstruction study: {points} points x 20 replicates x 2D+3D', paper_runs, paper_cost, longest, 1),
    (f'a calibration: {calib_iters} sequential evaluations of a {calib_points}-point 2D sweep x {calib_reps} replicates',
     calib_iters * calib_points * calib_reps, calib_iters * calib_points * calib_reps * g2['mean'], g2['longest'],
     calib_iters),
    ('10x larger sweep (10x the paper-scale study)', 10 * paper_runs, 10 * paper_cost, longest, 1),
]


def hours(s):
    return f'{s / 3600:.1f} h' if s >= 3600 else f'{s / 60:.0f} min' if s >= 60 else f'{s:.0f} s'


print('\nProjected wall time (T = max(cost / cores, longest run) per stage + plan expansion + merge):\n')
print('| workload | runs | core-hours | 2 cores | 64 cores | 1000 cores | store | merge |')
print('|---|---:|---:|---:|---:|---:|---:|---:|')
for label, runs, cost, worst, stages in workloads:
    merge_s = runs / merge['merge_runs_per_s']
    plan_s = runs / stages * plan['plan_ms_per_job'] / 1000
    cells = []
    for cores in (2, 64, 1000):
        t = stages * (max(cost / stages / cores, worst) + plan_s) + merge_s
        cells.append(hours(t))
    store_gb = runs * merge['bytes_per_run'] / 1e9
    print(f'| {label} | {runs} | {cost / 3600:.1f} | ' + ' | '.join(cells) + f' | {store_gb:.2f} GB | {hours(merge_s)} |')
print(f"\nMerge measured on synthetic stores: {int(merge['runs'])} runs in {int(merge['shards'])} shards "
      f"({int(merge['crossings_per_run'])} crossings per run) merged in {merge['merge_s']:.0f} s "
      f"({merge['merge_runs_per_s']:.0f} runs/s), merged again in {merge['remerge_s']:.0f} s adding nothing; "
      f"{merge['bytes_per_run'] / 1e3:.0f} kB per run. Plan expansion: {plan['plan_ms_per_job']:.2f} ms per job "
      f"(every share expands the whole list).")
