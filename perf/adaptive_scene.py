#!/usr/bin/env python3
"""An adaptive PD zone against the same scene run 100 % PD (issue 21, item 4; docs/coupling.md,
"The adaptive PD zone"): process wall time (median of --repeats, the two decks in turn), the
phases from timings.csv, switches and PD elements, and the crack paths compared as
tests/coupling/tstAdaptiveZone.hpp does: the nodes with damage >= 0.4 at the end, each crack
up to the other's tip (along --axis) within a distance of the other, in grid spacings.

usage: adaptive_scene.py --app PERISHELL [--pd DECK] [--adaptive DECK] [--repeats 3]
                         [--threads 2] [--out DIR]
       adaptive_scene.py --compare-only DIR   (paths of DIR/pd and DIR/adaptive, e.g. from a GPU)
Reading the fields needs h5py.
"""
import argparse
import csv
import glob
import math
import os
import re
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def run_once(app, deck, threads, directory):
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), OMP_PROC_BIND="false")
    start = time.perf_counter()
    result = subprocess.run([app, "run", deck, "--output", directory], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    wall = time.perf_counter() - start
    if result.returncode != 0:
        sys.exit(f"adaptive_scene: {app} run {deck} exited {result.returncode}:\n{result.stdout[-3000:]}")
    with open(os.path.join(directory, "timings.csv")) as handle:
        phases = {row["phase"]: float(row["seconds"]) for row in csv.DictReader(handle)}
    zone = re.search(r"adaptive PD zone\s+(\d+) -> (\d+) PD elements in (\d+) switches", result.stdout)
    steps = re.search(r"^\s+steps\s+(\d+)", result.stdout, re.MULTILINE)
    return {"wall": wall, "phases": phases, "steps": int(steps.group(1)) if steps else 0,
            "zone": zone.groups() if zone else None}


def crack_nodes(directory):
    import h5py
    with h5py.File(os.path.join(directory, "results_mesh.h5"), "r") as mesh:
        geometry = mesh["geometry"][:]
    last = sorted(glob.glob(os.path.join(directory, "results_[0-9]*.h5")))[-1]
    with h5py.File(last, "r") as fields:
        damage = fields["fields/damage"][:]
    return [tuple(geometry[i]) for i in range(len(damage)) if damage[i] >= 0.4]


def one_sided(source, target):
    worst = 0.0
    for p in source:
        worst = max(worst, min(math.dist(p, q) for q in target))
    return worst


def compare_paths(pd_dir, adaptive_dir, axis, spacing):
    pd, adaptive = crack_nodes(pd_dir), crack_nodes(adaptive_dir)
    if not pd or not adaptive:
        return f"crack paths: no crack node (damage >= 0.4) in {'the PD run' if not pd else 'the adaptive run'}"
    pd_tip, adaptive_tip = max(p[axis] for p in pd), max(p[axis] for p in adaptive)
    pd_to_adaptive = one_sided([p for p in pd if p[axis] <= adaptive_tip], adaptive)
    adaptive_to_pd = one_sided([p for p in adaptive if p[axis] <= pd_tip], pd)
    return (f"crack paths, each up to the other's tip: PD -> adaptive {pd_to_adaptive / spacing:.2f} dx, "
            f"adaptive -> PD {adaptive_to_pd / spacing:.2f} dx; tips {1e3 * pd_tip:.1f} and {1e3 * adaptive_tip:.1f} mm "
            f"({len(pd)} and {len(adaptive)} crack nodes)")


def deck_spacing(deck):
    with open(deck) as handle:
        found = re.search(r"^\s*spacing:\s*([0-9.eE+-]+)", handle.read(), re.MULTILINE)
    return float(found.group(1)) if found else float("nan")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--app")
    parser.add_argument("--pd", default=os.path.join(HERE, "decks", "glass_plate_wide.yaml"))
    parser.add_argument("--adaptive", default=os.path.join(HERE, "decks", "glass_plate_wide_adaptive.yaml"))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--axis", type=int, default=0, help="the crack runs along this axis (0 x, 1 y, 2 z)")
    parser.add_argument("--out", default="adaptive-scene")
    parser.add_argument("--compare-only", metavar="DIR")
    args = parser.parse_args()
    spacing = deck_spacing(args.adaptive)
    if args.compare_only:
        print(compare_paths(os.path.join(args.compare_only, "pd"), os.path.join(args.compare_only, "adaptive"),
                            args.axis, spacing))
        return
    if not args.app:
        parser.error("--app is required unless --compare-only is given")
    runs = {"pd": [], "adaptive": []}
    for _ in range(args.repeats):
        for name, deck in (("adaptive", args.adaptive), ("pd", args.pd)):
            runs[name].append(run_once(args.app, deck, args.threads, os.path.join(args.out, name)))
    print(f"{'model':10} {'wall s':>8} {'setup':>7} {'steps':>7} {'zone':>7} {'output':>7} {'steps n':>8}  zone")
    medians = {}
    for name in ("pd", "adaptive"):
        median = lambda key: statistics.median(r["phases"].get(key, 0.0) for r in runs[name])
        medians[name] = statistics.median(r["wall"] for r in runs[name])
        zone = runs[name][-1]["zone"]
        print(f"{name:10} {medians[name]:8.2f} {median('setup'):7.2f} {median('steps'):7.2f} "
              f"{median('adaptive-zone'):7.2f} {median('output'):7.2f} {runs[name][-1]['steps']:8d}  "
              + (f"{zone[0]} -> {zone[1]} PD elements in {zone[2]} switches" if zone else "-"))
    ratios = [a["wall"] / p["wall"] for a, p in zip(runs["adaptive"], runs["pd"])]
    print(f"adaptive / 100 % PD wall time: median {statistics.median(ratios):.3f} "
          f"(pairs {', '.join(f'{r:.3f}' for r in ratios)}; {args.repeats} repeats, {args.threads} threads)")
    try:
        print(compare_paths(os.path.join(args.out, "pd"), os.path.join(args.out, "adaptive"), args.axis, spacing))
    except ImportError:
        print(f"crack paths: h5py missing here; compare later with --compare-only {args.out}")


if __name__ == "__main__":
    main()
