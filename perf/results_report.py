#!/usr/bin/env python3
"""Writes docs/results.md (and docs/images/results/) from what perf/results.sh measured.

  python3 perf/results_report.py OUT [--docs DOCS]

OUT holds the parts of perf/results.sh (speedup/, accuracy/, examples/, each with its
machine.txt); a part that is missing is reported as not measured. Stdlib only.
"""
import argparse
import csv
import glob
import math
import os
import re
import shutil
import sys

# The paper's GPU times of its explicit examples at our decks' grids (model.md §7; Tables 5, 7,
# 8) [s], and its step count where stated (perf/speedup.py PAPER_STEPS: 50,000 steps of 0.1 µs
# for the steel plate at 1.75 mm; none for the prism and the cylinder). Shown beside our run,
# never divided by it: only the steel plate's run is as long as ours (50,000 steps).
PAPER_GPU = {"steel_plate_4_2_2": (10619, 50000), "hexagonal_prism_4_2_3": (4492, None),
             "cracked_cylinder_4_2_4": (4257, None)}
EXAMPLES = [
    ("glass_plate_4_1_2", "4.1.2 glass plate, crack branching"),
    ("steel_plate_4_2_2", "4.2.2 mild-steel plate under lateral load"),
    ("steel_plate_4_2_2_running", "4.2.2 loaded on to 2200 N until the crack runs"),
    ("hexagonal_prism_4_2_3", "4.2.3 hexagonal prism under pressure"),
    ("cracked_cylinder_4_2_4", "4.2.4 pre-cracked cylinder under lateral load"),
]
REGENERATE = "bash perf/results.sh build/cuda OUT"


class ReportError(Exception):
    pass


def machine(part_dir, path=None):
    path = path or os.path.join(part_dir, "machine.txt")
    if not os.path.exists(path):
        return "machine not recorded"
    facts = dict(line.split(": ", 1) for line in open(path, encoding="utf-8").read().splitlines() if ": " in line)
    gpu = facts.get("gpu") or "no GPU"
    return f"{facts.get('date', '?')}; GPU: {gpu}; CPU: {facts.get('cpu', '?')}"


class Images:
    """Copies figures next to the report and returns their relative links."""

    def __init__(self, docs):
        self.directory = os.path.join(docs, "images", "results")
        os.makedirs(self.directory, exist_ok=True)

    def link(self, source, name):
        if not os.path.exists(source):
            return None
        shutil.copyfile(source, os.path.join(self.directory, name))
        return f"images/results/{name}"


def speedup_section(out, images):
    part = os.path.join(out, "speedup")
    md = os.path.join(part, "speedup.md")
    if not os.path.exists(md):
        return ["## CPU vs GPU", "", "Not measured (`perf/results.sh BUILD OUT speedup`).", ""]
    text = open(md, encoding="utf-8").read().splitlines()
    body = [line.replace("## ", "### ", 1) if line.startswith("## ") else line for line in text[1:]]
    lines = ["## CPU vs GPU (`perf/speedup.py`)", "", f"Measured {machine(part)}."] + body
    chart = images.link(os.path.join(part, "speedup.png"), "speedup.png")
    if chart:
        lines += ["", "Left: CPU time over GPU time, ours per step (per linear solve), the paper's of one run "
                  "(one linear solve for 4.2.1). Right: GPU time per step (per linear solve), the paper's only "
                  "where its step count is known (4.2.1 all grids, 4.2.2 at 1.75 mm).", "",
                  f"![CPU/GPU speedup and GPU time per step against DOF, ours and the paper's]({chart})", ""]
    return lines


def accuracy_section(out, images):
    part = os.path.join(out, "accuracy")
    paths = sorted(glob.glob(os.path.join(part, "accuracy_*.csv")))
    if not paths:
        return ["## Speed against accuracy", "", "Not measured (`perf/results.sh BUILD OUT accuracy`).", ""]
    rows = [row for path in paths for row in csv.DictReader(open(path, encoding="utf-8"))]
    measured = []
    for path in paths:
        backend = os.path.basename(path)[len("accuracy_"):-len(".csv")]
        stamp = os.path.join(part, f"machine_{backend}.txt")
        measured.append(f"`--backend {backend}`: {machine(part, stamp)}")
    lines = ["## Speed against accuracy (`perf/accuracy_cost.cpp`, `perf/charts/speed_accuracy.py`)", "",
             "Measured " + "; ".join(measured) + ". Error against the references of model.md §8, wall time from "
             "model build to answer. Per case: every run, then its chart (log–log error against wall time, one "
             "curve per backend and swept parameter).", ""]
    for case in dict.fromkeys(row["case"] for row in rows):
        case_rows = [row for row in rows if row["case"] == case]
        lines += [f"### {case}: reference {case_rows[0]['reference']}", "",
                  "| backend | model | Δx [m] | m | PD ratio | kernel | free DOF | wall [s] | error | status |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for row in case_rows:
            error = row["error"]
            try:
                error = f"{float(error):.3g}" if math.isfinite(float(error)) else error
            except ValueError:
                pass
            lines.append(f"| {row['backend']} | {row['model']} | {row['spacing_m']} | {row['horizon_factor']} | "
                         f"{row['pd_ratio']} | {row['force_kernel']} | {row['free_dof']} | "
                         f"{float(row['wall_seconds']):.3g} | {error} | {row['status']} |")
        chart = images.link(os.path.join(part, f"accuracy_{case}.png"), f"accuracy_{case}.png")
        if chart:
            lines += ["", f"![{case}: error against wall time]({chart})"]
        lines.append("")
    return lines


def summary_value(log, name):
    found = re.search(rf"^\s*{re.escape(name)}\s{{2,}}(.+)$", log, flags=re.M)
    return found[1].strip() if found else "?"


def examples_section(out, images):
    part = os.path.join(out, "examples")
    if not os.path.isdir(part):
        return ["## The paper's explicit examples", "", "Not measured (`perf/results.sh BUILD OUT examples`).", ""]
    lines = ["## The paper's explicit examples, run to the end", "", f"Measured {machine(part)}, on the device "
             "backend. Images: `perf/charts/render_results.py damage` (damage and displacement magnitude), up to three output steps each. "
             "What each of the paper's figures shows, and why our 4.2.2 crack needs more than the paper's 1800 N: "
             "[fracture-examples.md](fracture-examples.md).", "",
             "| example | nodes | steps | wall time | steps' time per step | broken bonds | the paper's GPU (its run) |",
             "|---|---|---|---|---|---|---|"]
    figures = []
    for deck, title in EXAMPLES:
        log_path = os.path.join(part, f"{deck}.log")
        if not os.path.exists(log_path):
            lines.append(f"| {title} | not run | | | | | |")
            continue
        log = open(log_path, encoding="utf-8").read()
        nodes = re.search(r"model\s+([0-9,]+) nodes", log)
        steps = int(summary_value(log, "steps").split()[0])
        with open(os.path.join(part, deck, "timings.csv"), encoding="utf-8") as stream:
            phases = {row["phase"]: float(row["seconds"]) for row in csv.DictReader(stream)}
        paper, paper_steps = PAPER_GPU.get(deck, (None, None))
        if not paper:
            paper_text = "–"
        elif paper_steps:
            paper_text = f"{paper:,} s, {paper_steps:,} steps ({1e3 * paper / paper_steps:.3g} ms per step)"
        else:
            paper_text = f"{paper:,} s, run length not stated (not comparable)"
        lines.append(f"| {title} | {nodes[1] if nodes else '?'} | {steps:,} | {phases['total']:.3g} s "
                     f"(set-up {phases['setup']:.2g} s, output {phases['output']:.2g} s) | "
                     f"{1e3 * phases['steps'] / steps:.3g} ms | {summary_value(log, 'broken bonds')} | "
                     f"{paper_text} |")
        for field in ("damage", "displacement"):
            panel = images.link(os.path.join(part, deck, f"{deck}_{field}_panel.png"), f"{deck}_{field}.png")
            if panel:
                what = "damage" if field == "damage" else "displacement magnitude [m]"
                figures.append(f"**{title}**: {what}\n\n![{title}: {what}]({panel})\n")
    lines += [""] + figures
    speed = images.link(os.path.join(part, "glass_plate_4_1_2", "tip_speed.png"), "glass_tip_speed.png")
    if speed:
        history = os.path.join(part, "glass_plate_4_1_2", "history.csv")
        speeds = [float(row["crack-tip-speed"]) for row in csv.DictReader(open(history, encoding="utf-8"))]
        top = max((speed for speed in speeds if math.isfinite(speed)), default=float("nan"))
        lines += [f"Glass plate crack tip speed (largest between history rows: {top:.0f} m/s; Rayleigh speed "
                  f"about 3058 m/s, model.md §8):", "", f"![glass crack tip speed]({speed})", ""]
    opening = images.link(os.path.join(part, "steel_plate_4_2_2", "load_opening.png"), "steel_load_opening.png")
    if opening:
        lines += ["Steel plate load against crack opening:", "", f"![steel load opening]({opening})", ""]
    running = images.link(os.path.join(part, "steel_plate_4_2_2_running", "load_opening.png"),
                          "steel_running_load_opening.png")
    if running:
        lines += ["Steel plate loaded on to 2200 N:", "", f"![steel running load opening]({running})", ""]
    return lines


def main(arguments):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", help="the OUT directory of perf/results.sh")
    parser.add_argument("--docs", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs"))
    options = parser.parse_args(arguments)
    if not os.path.isdir(options.out):
        raise ReportError(f"{options.out}: no such directory")
    images = Images(options.docs)
    lines = ["# Results: speed and accuracy against the paper", "",
             "Everything below is regenerated by one command on a CUDA build (a CUDA build measures both "
             "backends; `--backend host` on 2 OpenMP threads is the CPU baseline):", "", "```sh",
             REGENERATE, "```", "",
             "Each part (`speedup`, `accuracy`, `examples`) can be run on its own (`perf/results.sh BUILD OUT PART`) "
             "and the report rebuilt from what is there. The paper's numbers are its own GPU and CPU (model.md §7).",
             ""]
    lines += speedup_section(options.out, images)
    lines += accuracy_section(options.out, images)
    lines += examples_section(options.out, images)
    path = os.path.join(options.docs, "results.md")
    with open(path + ".tmp", "w", encoding="utf-8") as stream:
        stream.write("\n".join(lines).rstrip() + "\n")
    os.replace(path + ".tmp", path)
    print(path)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv[1:]))
    except (ReportError, OSError, KeyError) as error:
        print(f"results_report: error: {error}", file=sys.stderr)
        sys.exit(1)
