#!/usr/bin/env python3
"""Prints the speed tables of the README from a Google Benchmark JSON file (scripts/bench.sh).

Per benchmark: the median CPU time over the repetitions and the spread (min-max). Per
comparison (Facet against Ceres or OpenCV on the same problem): each side's fastest setting
by median, and the ratio of the medians.
"""
import json
import re
import statistics
import sys
from collections import defaultdict

# (table title, Facet benchmark prefix, peer benchmark prefix, setting arguments ignored when
# matching problems: the fastest setting of each side is quoted)
COMPARISONS = [
    ("joint solve, drag frame (warm, 5 iterations)", "BM_JointInteractive", "BM_CeresInteractive"),
    ("joint solve from a perturbed start", "BM_JointCold", "BM_CeresCold"),
    ("joint solve drag frame, scaling", "BM_JointScaling", "BM_CeresScaling"),
    ("cold scene solve vs solvePnP", "BM_SolveSceneCold", "BM_OpenCvSolvePnPReference"),
    ("calibration from 40 3D points vs calibrateCamera", "BM_CalibrateFromPoints", "BM_OpenCvCalibrateCameraOneView"),
    ("fundamental matrix, RANSAC + LM vs findFundamentalMat RANSAC", "BM_FundamentalRansacAndRefine",
     "BM_OpenCvFindFundamentalMatRansac"),
    ("lines found for the user (detect, group, calibrate) vs OpenCV's LSD alone", "BM_DetectManhattanLines",
     "BM_OpenCvLineSegmentDetector"),
]
SETTING_ARGS = ("solver", "rebuild", "diagnostics")

UNIT_TO_MS = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}


def fmt_ms(ms):
    if ms >= 100:
        return f"{ms:.0f} ms"
    if ms >= 1:
        return f"{ms:.2f} ms"
    if ms >= 0.001:
        return f"{ms * 1000:.3g} us"
    return f"{ms * 1e6:.3g} ns"


def split_name(name):
    """'BM_X/a:1/solver:2' -> ('BM_X', problem key 'a:1', setting 'solver:2')."""
    parts = name.split("/")
    base, args = parts[0], parts[1:]
    problem = [a for a in args if a.split(":")[0] not in SETTING_ARGS and not a.startswith("repeats")]
    setting = [a for a in args if a.split(":")[0] in SETTING_ARGS]
    return base, "/".join(problem), "/".join(setting)


def main():
    path, load_before, load_after = sys.argv[1], sys.argv[2], sys.argv[3]
    data = json.load(open(path))
    runs = defaultdict(list)
    cpu_of_wall_runs = defaultdict(list)
    for b in data["benchmarks"]:
        if b.get("run_type") != "iteration":
            continue
        unit = UNIT_TO_MS[b["time_unit"]]
        # A benchmark that runs threads of its own (UseRealTime) is timed by the wall clock;
        # its CPU time (of all threads, MeasureProcessCPUTime) is shown beside.
        wall = "/real_time" in b["run_name"]
        runs[b["run_name"]].append((b["real_time"] if wall else b["cpu_time"]) * unit)
        if wall:
            cpu_of_wall_runs[b["run_name"]].append(b["cpu_time"] * unit)
    ctx = data["context"]
    print(f"machine: {ctx.get('num_cpus')} CPUs at {ctx.get('mhz_per_cpu')} MHz; "
          f"load average before {load_before}, after {load_after}; "
          f"{max(len(v) for v in runs.values())} repetitions, random interleaving; CPU time, "
          f"wall-clock time for the .../real_time ones")
    print()
    print("| benchmark | median | min - max | CPU of all threads (median) |")
    print("|---|---|---|---|")
    for name, times in runs.items():
        cpu = cpu_of_wall_runs.get(name)
        cpu_text = fmt_ms(statistics.median(cpu)) if cpu else ""
        print(f"| {name} | {fmt_ms(statistics.median(times))} | {fmt_ms(min(times))} - {fmt_ms(max(times))} | "
              f"{cpu_text} |")
    for title, facet, peer in COMPARISONS:
        sides = {facet: defaultdict(list), peer: defaultdict(list)}
        for name, times in runs.items():
            base, problem, setting = split_name(name)
            if base in sides:
                sides[base][problem].append((statistics.median(times), min(times), max(times), setting))
        problems = [p for p in sides[facet] if p in sides[peer]]
        if not problems and sides[facet] and len(sides[peer]) == 1:
            # A peer measured on one fixed problem (e.g. solvePnP): compare every Facet row with it.
            only = next(iter(sides[peer]))
            for p in list(sides[facet]):
                sides[peer][p] = sides[peer][only]
            problems = list(sides[facet])
        if not problems:
            continue
        print()
        print(f"{title}:")
        print()
        print("| problem | Facet (fastest setting) | spread | peer (fastest setting) | spread | Facet / peer |")
        print("|---|---|---|---|---|---|")
        for p in problems:
            f = min(sides[facet][p])
            q = min(sides[peer][p])
            print(f"| {p or '-'} | {fmt_ms(f[0])} ({f[3] or '-'}) | {fmt_ms(f[1])} - {fmt_ms(f[2])} | "
                  f"{fmt_ms(q[0])} ({q[3] or '-'}) | {fmt_ms(q[1])} - {fmt_ms(q[2])} | {f[0] / q[0]:.2f} |")


if __name__ == "__main__":
    main()
