#!/usr/bin/env python3
"""Print the Performance section (Markdown) from a gapflow_bench JSON file.

    scripts/perf_table.py [bench/baselines/baseline.json]

Medians over the repetitions (Google Benchmark's median aggregate; the single
run when there was one repetition). The machine line comes from the file's
context (written by bench/bench_main.cpp: nproc, CPU model, load average at the
start) and from the uptime record next to it (baseline.load.txt / latest.load.txt),
so the table describes the machine that produced the numbers, not the one
printing them. Python 3 standard library only.
"""
import json
import os
import re
import sys


def load_runs(path):
    """{run_name: {"median": entry, "cv": entry, "reps": [entries]}}."""
    with open(path) as f:
        data = json.load(f)
    runs = {}
    for b in data.get("benchmarks", []):
        r = runs.setdefault(b.get("run_name", b["name"]), {"reps": []})
        if b.get("run_type") == "aggregate":
            r[b["aggregate_name"]] = b
        else:
            r["reps"].append(b)
    for r in runs.values():
        if "median" not in r and r["reps"]:
            r["median"] = r["reps"][0]
    return data.get("context", {}), runs


def cpu_model_here():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown CPU"


def seconds(entry, field):
    unit = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}[entry.get("time_unit", "ns")]
    return entry[field] * unit


def cv_percent(run, field):
    cv = run.get("cv")
    return f"{100 * cv[field]:.1f} %" if cv and field in cv else "-"


def reps(run):
    n = len(run["reps"]) or run["median"].get("repetitions", 1)
    return n


def machine_lines(ctx, path):
    nproc = ctx.get("nproc", ctx.get("num_cpus", os.cpu_count()))
    cpu = ctx.get("cpu_model") or cpu_model_here()
    date = ctx.get("date", "?")[:10]
    lines = [f"Machine: {nproc} cores (`nproc`), {cpu} @ {ctx.get('mhz_per_cpu', '?')} MHz; measured {date}; "
             f"gapflow {ctx.get('gapflow_code_version', '?')} ({ctx.get('gapflow_build', '?')} build)."]
    # Load: the uptime record next to the JSON (before and after), else the context.
    side = re.sub(r"\.json$", ".load.txt", path)
    loads = []
    if os.path.exists(side):
        with open(side) as f:
            for line in f:
                m = re.search(r"load average: ([\d.]+), ([\d.]+), ([\d.]+)", line)
                if m and line.startswith(("before:", "after:")):
                    loads.append(f"{', '.join(m.groups())} {line.split(':')[0]} the run")
    if not loads and ctx.get("loadavg_at_start"):
        loads.append(f"{', '.join(ctx['loadavg_at_start'].split()[:3])} at the start")
    if loads:
        lines.append(f"Load average (1, 5, 15 min): {'; '.join(loads)}. Above the core count the machine "
                     "was shared with other jobs: wall times suffer most, the step costs are CPU time.")
    if ctx.get("gapflow_set"):
        lines.append(f"**Experiment**: every scene had `--set {ctx['gapflow_set']}`.")
    return lines


def step_table(runs):
    rows = {}
    for name, r in runs.items():
        m = re.match(r"Step(2D|3D)(Large)?/particles:(\d+)/", name)
        if m and "median" in r:
            rows.setdefault(int(m.group(3)), {})[m.group(1)] = r
    if not rows:
        return []
    out = ["| particles | 2D ns / particle-step | 2D ms / step | 3D ns / particle-step | 3D ms / step |",
           "|---:|---:|---:|---:|---:|"]
    for n in sorted(rows):
        cells = [f"{n}"]
        for model in ("2D", "3D"):
            r = rows[n].get(model)
            if r is None:
                cells += ["-", "-"]
                continue
            med = r["median"]
            cells.append(f"{med['ns_per_particle_step']:.0f} (cv {cv_percent(r, 'cpu_time')})")
            cells.append(f"{1e3 * seconds(med, 'cpu_time'):.2f}")
        out.append("| " + " | ".join(cells) + " |")
    return out


def runs_table(runs):
    out = ["| benchmark | result (median) | repetitions | physics check |", "|---|---|---:|---|"]
    for name in sorted(runs):
        r = runs[name]
        med = r.get("median")
        if med is None:
            continue
        if name.startswith("Discharge"):
            model = "2D" if name.startswith("Discharge2D") else "3D"
            out.append(f"| paper medium discharge, {model} (1551 spheres, settle + all pass) | "
                       f"{med['sim_s_per_wall_s']:.2f} simulated s per wall s "
                       f"({med['sim_s_per_cpu_s']:.2f} per CPU s); {seconds(med, 'real_time'):.1f} s wall per run "
                       f"for {med['sim_s']:.2f} s | {reps(r)} | J = {med['check_J_paper']:.2f} /s, "
                       f"{med['check_passed']:.0f} passed, {med['check_escaped']:.0f} escaped |")
        elif name.startswith("Study/"):
            workers = re.search(r"workers:(\d+)", name).group(1)
            eff = f"; parallel efficiency {100 * med['parallel_efficiency']:.0f} %" if "parallel_efficiency" in med else ""
            out.append(f"| study throughput, {workers} worker{'s' if workers != '1' else ''} "
                       f"({med['runs']:.0f} short 2D runs) | {med['runs_per_min']:.0f} runs/min (wall){eff} | "
                       f"{reps(r)} | {med['check_crossings']:.0f} crossings |")
        elif name.startswith("Measurement"):
            model = "2D" if name.startswith("Measurement2D") else "3D"
            out.append(f"| measurement cost, {model} (paper medium, flowing) | "
                       f"{100 * med['measure_fraction']:.1f} % of stepping; "
                       f"{med['measure_ns_per_particle']:.0f} ns per particle per step "
                       f"(stepping {med['step_ns_per_particle']:.0f}) | {reps(r)} | "
                       f"{med['check_passed']:.0f} crossings, {med['check_escaped']:.0f} escaped |")
    return out if len(out) > 2 else []


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "bench", "baselines", "baseline.json")
    path = os.path.normpath(path)
    ctx, runs = load_runs(path)
    print("### Performance")
    print()
    for line in machine_lines(ctx, path):
        print(line)
        print()
    steps = step_table(runs)
    if steps:
        print("Step cost in a flowing hopper (paper medium scenario, board enlarged for the count; "
              "CPU time, median; 3D above 5000 particles is opt-in):")
        print()
        print("\n".join(steps))
        print()
    other = runs_table(runs)
    if other:
        print("\n".join(other))
        print()
    print(f"Source: `{os.path.relpath(path)}`, produced by `scripts/bench.sh`; table by `scripts/perf_table.py`.")


if __name__ == "__main__":
    main()
