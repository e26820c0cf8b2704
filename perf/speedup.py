#!/usr/bin/env python3
"""CPU-vs-GPU speedup of the paper's examples (Tables 3-5, 7, 8), from one perishell binary.

Runs each case deck of apps/cases at each grid spacing with `perishell run --backend host`
(Kokkos' host space, OpenMP on --cpu-threads threads: the CPU baseline) and with
`--backend device` (CUDA in a CUDA build), reads the per-phase wall times each run writes
to timings.csv, and writes:

  OUT/speedup.csv   one row per case, grid, backend and phase: the median over repeats
  OUT/speedup.md    per case: time per step (or per linear solve) on each backend and their
                    ratio, the full run's time (measured, or extrapolated from the steps
                    run), and the paper's GPU and CPU times for the same case and grid;
                    ours against the paper's only per step (per linear solve), where the
                    paper's step count is known (PAPER_STEPS), else "not comparable";
                    per case a phase table in the style of the paper's Table 3
  OUT/speedup.png   against the paper's DOF count (if matplotlib is there): CPU time / GPU
                    time, ours (per step) beside the paper's (its CPU and GPU run of one
                    case and grid); and GPU time per step (per linear solve), ours beside
                    the paper's where its step count is known

Explicit cases run --cpu-steps steps on the CPU and --gpu-steps on the GPU (0: the whole
deck); implicit ones one increment on both. Time per step is the `steps` phase over the
steps run; the full run is extrapolated as setup + per step x the deck's steps when fewer
were run. Both DOF counts are reported: the paper's (elements x 24, model.md §7) and the true
free DOF. Stdlib only, so it runs on the GPU machine as it is.

  python3 perf/speedup.py --app build/cuda/apps/perishell --out speedup [--cases steel,prism]
      [--repeats 3] [--cpu-threads 2] [--cpu-steps 20] [--gpu-steps 0] [--long-run 30] [--quick]
      [--spacing DX] [--append]
"""
import argparse
import csv
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

CASES_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "apps", "cases")

# The paper's tables (model.md §7; Table 8's last CPU entry reads "14,178" in the paper's
# text, a dropped digit: its speedup 9.72 x 14,586 s gives 141,776 s).
CASES = {
    "pressed": {
        "deck": "pressed_plate_4_2_1.yaml", "kind": "implicit",
        "title": "4.2.1 pressed plate, 50 % PD: one linear solve (paper Table 4)",
        "grids": [  # spacing [m], paper DOF, paper GPU s, paper CPU s, run on the CPU
            (0.5e-3, 259200, 163, 1229, True),
            (0.25e-3, 1036800, 347, 3148, False),  # the CPU: docs/implicit.md (perf/implicit_solve)
            (0.1e-3, 6480000, 11329, 115293, False),
        ],
        "phase_paper": {  # Table 3: one iteration step at 0.5 mm, CPU and GPU [s]
            "assembly": (11.16, 4.23), "constraints": (0.03, 0.01),
            "linear solve": (1228.65, 163.82), "stress update": (0.74, 0.16)},
    },
    "steel": {
        "deck": "steel_plate_4_2_2.yaml", "kind": "explicit",
        "title": "4.2.2 mild-steel plate, 100 % PD, 50,000 steps (paper Table 5)",
        # 1.015 and 0.7 mm keep the crack line x = 101.5 mm on a node column (the paper's
        # finer grids: 989,016 and 1,759,920 DOF, about 1.0 and 0.75 mm).
        "grids": [(1.75e-3, 322944, 10619, 74645, True), (1.015e-3, 989016, 45743, 359189, True),
                  (0.7e-3, 1759920, 60452, 497297, True)],
    },
    "prism": {
        "deck": "hexagonal_prism_4_2_3.yaml", "kind": "explicit",
        "title": "4.2.3 hexagonal prism, 100 % PD (paper Table 7)",
        "grids": [(2.5e-3, 456760, 4492, 33102, True), (1.5e-3, 1256976, 9073, 78329, True),
                  (1.0e-3, 2854800, 18276, 173787, True)],
    },
    "cylinder": {
        "deck": "cracked_cylinder_4_2_4.yaml", "kind": "explicit",
        "title": "4.2.4 pre-cracked cylinder, 100 % PD (paper Table 8)",
        "grids": [(4.5e-3, 446904, 4257, 33274, True), (3.0e-3, 1005528, 8447, 72391, True),
                  (2.0e-3, 2262456, 14586, 141776, True)],
    },
    "glass": {
        "deck": "glass_plate_4_1_2.yaml", "kind": "explicit",
        "title": "4.1.2 glass plate, 100 % PD (no paper timing)",
        "grids": [(0.5e-3, None, None, None, True)],
    },
}


# The paper's step count per timed run, where it is stated or can be inferred; its times are
# compared with ours only per step (explicit) or per linear solve (implicit), never run
# against run, because our decks' run lengths are our own (the prism's and the cylinder's
# 1 ms) and the paper does not state most of its own. Paper text: ../shared/paper (line
# numbers of its text version).
#   pressed: Table 4 "only provides statistics for the time of solving linear equations once"
#            (l. 730): its times are per linear solve already (0.5 mm: Table 3's "one iteration
#            step", linear solve 1228.65 / 163.82 s, l. 708-712), compared with ours per
#            linear solve (preconditioner + PCG per Newton iteration).
#   steel:   "Δx = 1.75 mm ... 13,456 elements ... the time step is set to 0.1 µs ... After
#            50,000 incremental steps, the load is gradually increased to 1800 N" (l. 749);
#            Table 5's 1.75 mm row is that model (322,944 = 13,456 x 24 DOF, l. 774). For its
#            finer grids (l. 759, 775-776) neither the steps nor the time step is stated.
#   prism, cylinder: no time step, duration or step count (l. 782-784, 788, 803).
#   glass:   no timing at all (l. 686-696).
PAPER_STEPS = {"steel": {1.75e-3: 50000}}
PAPER_STEPS_NOTE = {
    "pressed": "Ours vs paper: per linear solve; the paper's Table 4 times one linear solve (\"only provides "
               "statistics for the time of solving linear equations once\", its Section 4.2.1), ours are "
               "preconditioner + PCG per Newton iteration of the first increment.",
    "steel": "Ours vs paper: per step. The paper states 50,000 steps of 0.1 µs for its 1.75 mm model (\"After "
             "50,000 incremental steps, the load is gradually increased to 1800 N\", Section 4.2.2), the "
             "model of Table 5's first row (13,456 elements × 24 = 322,944 DOF): its times over 50,000. For "
             "the finer grids it states neither steps nor time step: not comparable (our deck keeps 50,000 "
             "steps of 0.1 µs on every grid, the paper may not have).",
    "prism": "Not comparable with the paper: it states no time step, duration or step count for this example "
             "(Section 4.2.3), and our run length (1 ms) is ours.",
    "cylinder": "Not comparable with the paper: it states no time step, duration or step count for this "
                "example (Section 4.2.4), and our run length (1 ms) is ours.",
}
NOT_COMPARABLE = "not comparable"


def paper_per_unit(case, spacing, paper_seconds):
    """The paper's seconds per step (explicit) or per linear solve (implicit: Table 4 is one
    solve); None where its step count is unknown or it has no time."""
    if paper_seconds is None:
        return None
    if CASES[case]["kind"] == "implicit":
        return paper_seconds
    steps = PAPER_STEPS.get(case, {}).get(spacing)
    return paper_seconds / steps if steps else None


class SpeedupError(Exception):
    pass


def steel_flanks_at_spacing(text, spacing, deck_path):
    """The steel plate's flank node sets and forces on another grid: the node columns either
    side of the crack line x = 101.5 mm, and the deck's 1800 N per flank shared by their nodes."""
    crack_x, y_low, y_high, total = 0.1015, 0.0865, 0.1165, 1800.0
    columns = {"left-flank": crack_x - spacing, "right-flank": crack_x}
    for name, x in columns.items():
        text, count = re.subn(rf"^(\s+{name}: {{box: {{min: \[)[^,]+(, [^,]+, [^\]]+\], max: \[)[^,]+",
                              lambda m: f"{m.group(1)}{x - spacing / 4:.6g}{m.group(2)}{x + spacing / 4:.6g}", text,
                              count=1, flags=re.M)
        if count != 1:
            raise SpeedupError(f"{deck_path}: no '{name}' box to move")
    nodes = math.floor(y_high / spacing + 1e-9) - math.ceil(y_low / spacing - 1e-9) + 1
    for name, sign in (("lift-left-flank", 1.0), ("push-right-flank", -1.0)):
        text, count = re.subn(rf"^(\s+{name}: {{.*vector: \[0.0, 0.0, )[-+0-9.eE]+",
                              lambda m: f"{m.group(1)}{sign * total / nodes!r}", text, count=1, flags=re.M)
        if count != 1:
            raise SpeedupError(f"{deck_path}: no '{name}' load to scale")
    return text


def deck_at_spacing(deck_path, spacing, directory):
    """The deck with mesh.spacing replaced (the first `spacing:` key), written to directory;
    the steel plate's flanks follow the grid."""
    with open(deck_path, encoding="utf-8") as stream:
        text = stream.read()
    new_text, count = re.subn(r"^(\s+spacing:\s*)[-+0-9.eE]+", lambda m: f"{m.group(1)}{spacing!r}", text,
                              count=1, flags=re.M)
    if count != 1:
        raise SpeedupError(f"{deck_path}: no 'spacing:' key to set")
    if os.path.basename(deck_path) == CASES["steel"]["deck"]:
        new_text = steel_flanks_at_spacing(new_text, spacing, deck_path)
    path = os.path.join(directory, f"{os.path.basename(deck_path)[:-5]}_{spacing * 1e3:g}mm.yaml")
    with open(path, "w", encoding="utf-8") as stream:
        stream.write(new_text)
    return path


def run_once(app, deck, backend, steps, threads, output, phase_times=False):
    """One `perishell run`; returns (phases {name: seconds}, facts parsed from the log)."""
    command = [app, "run", deck, "--backend", backend, "--output", output]
    if steps:
        command += ["--max-steps", str(steps)]
    if phase_times:
        command.append("--phase-times")
    environment = dict(os.environ, OMP_NUM_THREADS=str(threads), OMP_PROC_BIND="false")
    started = time.time()
    result = subprocess.run(command, capture_output=True, text=True, env=environment)
    if result.returncode != 0:
        raise SpeedupError(f"{' '.join(command)} exited {result.returncode}:\n{result.stdout[-2000:]}"
                           f"{result.stderr[-2000:]}")
    log = result.stdout
    phases = {}
    with open(os.path.join(output, "timings.csv"), encoding="utf-8") as stream:
        for row in csv.DictReader(stream):
            phases[row["phase"]] = float(row["seconds"])
    facts = {"process_seconds": time.time() - started}
    model = re.search(r"model\s+([0-9,]+) nodes, ([0-9,]+) quads, PD ratio ([0-9.]+) %, ([0-9,]+) free DOF", log)
    if not model:
        raise SpeedupError(f"{' '.join(command)}: no model line in its output")
    facts["nodes"], facts["elements"] = int(model[1].replace(",", "")), int(model[2].replace(",", ""))
    facts["free_dof"] = int(model[4].replace(",", ""))
    counted = re.search(r"\b(steps|increments)\s+([0-9]+)(?: of ([0-9]+))?", log.split("run summary", 1)[-1])
    facts["steps"] = int(counted[2])
    facts["deck_steps"] = int(counted[3] or counted[2])
    newton = re.search(r"Newton iterations\s+([0-9]+)", log)
    facts["newton"] = int(newton[1]) if newton else None
    backend_name = re.search(r"backend\s+(\S+)", log.split("run summary", 1)[-1])
    facts["backend_name"] = backend_name[1] if backend_name else backend
    return phases, facts


def measure(app, case, spacing, backend, steps, threads, repeats, work, split_steps, long_run):
    """Median phases over repeats (a single run when the first takes over long_run seconds);
    with split_steps, one more run with --phase-times adds the explicit step's phases (kept
    out of the repeats: its synchronisations slow the steps)."""
    deck = deck_at_spacing(os.path.join(CASES_DIR, CASES[case]["deck"]), spacing, work)

    def run(index, phase_times=False):
        output = os.path.join(work, f"{case}-{spacing:g}-{backend}-{index}")
        result = run_once(app, deck, backend, steps, threads, output, phase_times)
        shutil.rmtree(output, ignore_errors=True)
        print(f"speedup: {case} {spacing * 1e3:g} mm {backend} run {index + 1}{' (phase times)' if phase_times else ''}"
              f": {result[0]['total']:.3f} s", file=sys.stderr, flush=True)
        return result

    runs = [run(0)]
    if runs[0][0]["total"] <= long_run:
        runs += [run(index) for index in range(1, repeats)]
    phases = {name: statistics.median(r[0][name] for r in runs) for name in runs[0][0]}
    if split_steps:
        timed = run(len(runs), phase_times=True)[0]
        for name in ("forces", "integration", "monitor"):
            if name in timed:
                phases[name] = timed[name]
    facts = dict(runs[0][1], repeats=len(runs))
    return phases, facts


def per_step(kind, phases, facts):
    """Seconds per step (explicit) or per linear solve (implicit: preconditioner + PCG per
    Newton iteration, the paper's Table 4 measure)."""
    if kind == "implicit":
        return (phases["preconditioner"] + phases["linear-solve"]) / max(1, facts["newton"])
    return phases["steps"] / facts["steps"]


def full_run(kind, phases, facts):
    """(seconds, extrapolated?) for the deck's whole run."""
    if facts["steps"] == facts["deck_steps"]:
        return phases["total"], False
    if kind == "implicit":  # every increment as the first
        run = phases["total"] - phases["setup"]
        return phases["setup"] + run * facts["deck_steps"] / facts["steps"], True
    return phases["setup"] + per_step(kind, phases, facts) * facts["deck_steps"], True


def seconds_text(value, extrapolated=False):
    if value is None:
        return "–"
    text = f"{value:.3g}" if value < 100 else f"{value:,.0f}"
    return text + (" (extrap.)" if extrapolated else "")


def ratio_text(numerator, denominator):
    if numerator is None or denominator is None or denominator <= 0:
        return "–"
    return f"{numerator / denominator:.1f}×"


def paper_ratio_text(paper_seconds, paper_unit, ours):
    """The paper's time per step (per linear solve) over ours: '–' where either has no time,
    'not comparable' where the paper has a time but not its step count."""
    if paper_seconds is None or ours is None or ours <= 0:
        return "–"
    if paper_unit is None:
        return NOT_COMPARABLE
    value = paper_unit / ours
    return f"{value:,.0f}×" if value >= 100 else f"{value:.1f}×"


def phase_rows(kind, cpu, gpu):
    if kind == "implicit":
        names = [("setup (neighbour search, bonds, pattern)", "setup"), ("assembly", "assembly"),
                 ("constraints", "constraints"), ("linear solve (PCG)", "linear-solve"),
                 ("preconditioner (AMG set-up)", "preconditioner"), ("stress update (internal forces)",
                                                                      "internal-forces"),
                 ("update (u, R)", "update"), ("output", "output"), ("total", "total")]
    else:  # the runs took different numbers of steps: step phases per step
        names = [("setup (neighbour search, bonds, critical step)", "setup"),
                 ("stress update (forces), per step", "forces"), ("integration, per step", "integration"),
                 ("energy monitor, per step", "monitor"), ("all steps, per step", "steps")]
    per_step_phases = {"forces", "integration", "monitor", "steps"}

    def value(measured, key):
        if not measured or key not in measured[0]:
            return None
        seconds = measured[0][key]
        return seconds / measured[1]["steps"] if kind == "explicit" and key in per_step_phases else seconds

    rows = []
    for label, key in names:
        c, g = value(cpu, key), value(gpu, key)
        if c is not None or g is not None:
            rows.append((label, c, g))
    return rows


def measured_cases(results):
    """The cases in results, in the order of CASES."""
    return [case for case in CASES if any(key[0] == case for key in results)]


def load_previous(out):
    """The results of an earlier run from OUT/speedup.csv ({} when there is none)."""
    path = os.path.join(out, "speedup.csv")
    results = {}
    if not os.path.exists(path):
        return results
    with open(path, encoding="utf-8") as stream:
        for row in csv.DictReader(stream):
            key = (row["case"], float(row["spacing_m"]))
            entry = results.setdefault(key, {"spacing": key[1],
                                             "paper_dof": int(row["paper_dof"]) if row["paper_dof"] else None})
            facts = {"free_dof": int(row["free_dof"]), "nodes": int(row["nodes"]), "steps": int(row["steps"]),
                     "elements": int(row["elements"]),
                     "deck_steps": int(row["deck_steps"]), "backend_name": row["backend"],
                     "newton": int(row["newton_iterations"]) if row["newton_iterations"] else None,
                     "repeats": int(row["repeats"])}
            entry.setdefault(row["role"], ({}, facts))[0][row["phase"]] = float(row["seconds"])
    return results


def write_outputs(out, results, options, runs):
    csv_path = os.path.join(out, "speedup.csv")
    with open(csv_path + ".tmp", "w", newline="", encoding="utf-8") as stream:
        writer = csv.writer(stream)
        writer.writerow(["case", "spacing_m", "paper_dof", "elements", "free_dof", "nodes", "role", "backend", "threads", "steps",
                         "deck_steps", "newton_iterations", "repeats", "phase", "seconds"])
        for (case, spacing), entry in results.items():
            for backend in ("host", "device"):
                measured = entry.get(backend)
                if not measured:
                    continue
                phases, facts = measured
                for phase, seconds in phases.items():
                    writer.writerow([case, spacing, entry["paper_dof"] or "", facts["elements"], facts["free_dof"],
                                     facts["nodes"],
                                     backend, facts["backend_name"], options.cpu_threads, facts["steps"],
                                     facts["deck_steps"], facts["newton"] or "", facts["repeats"], phase,
                                     f"{seconds:.9g}"])
    os.replace(csv_path + ".tmp", csv_path)

    lines = ["# CPU vs GPU: the paper's examples", ""] + [f"{line}." for line in runs] + [
        "",
        f"CPU = `--backend host` on {options.cpu_threads} OpenMP threads, GPU = `--backend device` (one binary); "
        f"medians of {options.repeats} runs (one where a run takes over {options.long_run:g} s). DOF: the paper's "
        "count for its grid, ours by the same rule (elements × 24), and our free DOF. Per step: the explicit steps' "
        "time over the steps run; implicit: preconditioner + PCG per Newton iteration of the first increment "
        "(the paper's \"one linear solve\"). Full run: the deck's whole run, extrapolated from the steps run where "
        "marked. Ours vs paper: the paper's time per step (per linear solve) over ours, only where the paper's "
        "step count is known (each table's note says how); where it is not, \"not comparable\": our decks' run "
        "lengths are our own, so full runs are not compared. Phase tables: the paper's Table 3 columns; explicit "
        "step phases per step, from one more run with `--phase-times` (a synchronisation per phase).", ""]
    for case in measured_cases(results):
        spec = CASES[case]
        kind = spec["kind"]
        unit = "per linear solve" if kind == "implicit" else "per step"
        paper_what = "paper CPU per linear solve [s] | paper GPU per linear solve [s] | paper ratio" \
            if kind == "implicit" else "paper CPU [s] | paper GPU [s] | paper ratio | paper steps"
        lines += [f"## {spec['title']}", "",
                  f"| Δx [mm] | paper DOF | our elements × 24 | free DOF | CPU {unit} [s] | GPU {unit} [s] | ratio | "
                  f"CPU full run [s] | GPU full run [s] | ratio | {paper_what} | ours vs paper CPU, {unit} | "
                  f"ours vs paper GPU, {unit} |",
                  "|---" * (15 if kind == "implicit" else 16) + "|"]
        paper = {grid[0]: grid[1:4] for grid in spec["grids"]}
        spacings = sorted((key[1] for key in results if key[0] == case), reverse=True)
        for spacing in spacings:
            entry = results[(case, spacing)]
            paper_dof, paper_gpu, paper_cpu = paper.get(spacing, (None, None, None))
            cpu, gpu = entry.get("host"), entry.get("device")
            facts = (cpu or gpu)[1]
            cpu_step = per_step(kind, *cpu) if cpu else None
            gpu_step = per_step(kind, *gpu) if gpu else None
            cpu_full, cpu_extra = full_run(kind, *cpu) if cpu else (None, False)
            gpu_full, gpu_extra = full_run(kind, *gpu) if gpu else (None, False)
            # Ours against the paper's only per step (per linear solve: Table 4 times one
            # solve), never full run against full run: the run lengths differ or are unknown.
            steps_cell = ""
            if kind == "explicit":
                paper_steps = PAPER_STEPS.get(case, {}).get(spacing)
                steps_cell = " | " + (f"{paper_steps:,}" if paper_steps else "not stated" if paper_gpu else "–")
            lines.append(
                f"| {spacing * 1e3:g} | {paper_dof and f'{paper_dof:,}' or '–'} | {24 * facts['elements']:,} | "
                f"{facts['free_dof']:,} | "
                f"{seconds_text(cpu_step)} | {seconds_text(gpu_step)} | {ratio_text(cpu_step, gpu_step)} | "
                f"{seconds_text(cpu_full, cpu_extra)} | {seconds_text(gpu_full, gpu_extra)} | "
                f"{ratio_text(cpu_full, gpu_full)} | {seconds_text(paper_cpu)} | {seconds_text(paper_gpu)} | "
                f"{ratio_text(paper_cpu, paper_gpu)}{steps_cell} | "
                f"{paper_ratio_text(paper_cpu, paper_per_unit(case, spacing, paper_cpu), cpu_step)} | "
                f"{paper_ratio_text(paper_gpu, paper_per_unit(case, spacing, paper_gpu), gpu_step)} |")
        if case in PAPER_STEPS_NOTE:
            lines += ["", PAPER_STEPS_NOTE[case]]
        both = [spacing for spacing in spacings if results[(case, spacing)].get("host")
                and results[(case, spacing)].get("device")]
        if both:
            spacing = both[0]
            cpu, gpu = results[(case, spacing)]["host"], results[(case, spacing)]["device"]
            what = "one increment" if kind == "implicit" else \
                f"{cpu[1]['steps']} CPU and {gpu[1]['steps']} GPU steps; step phases per step"
            lines += ["", f"Phases at Δx {spacing * 1e3:g} mm ({what}):", "",
                      "| phase | CPU [s] | GPU [s] | ratio |", "|---|---|---|---|"]
            for label, c, g in phase_rows(kind, cpu, gpu):
                lines.append(f"| {label} | {seconds_text(c)} | {seconds_text(g)} | {ratio_text(c, g)} |")
            if "phase_paper" in spec:
                lines += ["", "The paper's Table 3 (one Newton iteration at 0.5 mm, 50 % PD; CPU / GPU [s]): " +
                          ", ".join(f"{k} {c} / {g}" for k, (c, g) in spec["phase_paper"].items()) + "."]
        lines.append("")
    md_path = os.path.join(out, "speedup.md")
    with open(md_path + ".tmp", "w", encoding="utf-8") as stream:
        stream.write("\n".join(lines))
    os.replace(md_path + ".tmp", md_path)
    paths = [csv_path, md_path]
    chart = write_chart(out, results, options)
    if chart:
        paths.append(chart)
    return paths


def write_chart(out, results, options):
    """Two panels against DOF (the paper's count where it has the grid, else ours by its rule):
    CPU time / GPU time, ours per step (per linear solve) and the paper's of one run; and GPU
    time per step (per linear solve), the paper's only where its step count is known. No
    panel divides one run length by another."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("speedup: matplotlib is missing; no chart", file=sys.stderr)
        return None
    figure, (left, right) = plt.subplots(1, 2, figsize=(12, 6))
    for index, case in enumerate(measured_cases(results)):
        spec = CASES[case]
        kind = spec["kind"]
        paper_grids = {grid[0]: grid[1:4] for grid in spec["grids"]}
        ours_speedup, paper_speedup, ours_gpu, paper_gpu_unit = [], [], [], []
        for spacing, paper_dof, paper_gpu, paper_cpu, _ in spec["grids"]:
            if paper_dof and paper_gpu and paper_cpu:
                paper_speedup.append((paper_dof, paper_cpu / paper_gpu))
            unit = paper_per_unit(case, spacing, paper_gpu)
            if paper_dof and unit:
                paper_gpu_unit.append((paper_dof, unit))
        for (measured_case, spacing), entry in sorted(results.items(), key=lambda item: item[0][1], reverse=True):
            if measured_case != case:
                continue
            facts = (entry.get("device") or entry.get("host"))[1]
            dof = paper_grids.get(spacing, (None,))[0] or 24 * facts["elements"]
            if entry.get("device"):
                ours_gpu.append((dof, per_step(kind, *entry["device"])))
                if entry.get("host"):
                    ours_speedup.append((dof, per_step(kind, *entry["host"]) / per_step(kind, *entry["device"])))
        colour = f"C{index}"
        unit_name = "per linear solve" if kind == "implicit" else "per step"
        if ours_speedup:
            left.plot(*zip(*ours_speedup), "o-", color=colour,
                      label=f"{case}: perishell {unit_name} (CPU {options.cpu_threads} thr. / GPU)")
        if paper_speedup:
            left.plot(*zip(*paper_speedup), "s--", color=colour, alpha=0.6,
                      label=f"{case}: paper, {'one linear solve' if kind == 'implicit' else 'one run'} "
                            "(its CPU / its GPU)")
        if ours_gpu:
            right.plot(*zip(*ours_gpu), "o-", color=colour, label=f"{case}: perishell GPU, {unit_name}")
        if paper_gpu_unit:
            right.plot(*zip(*paper_gpu_unit), "s--", color=colour, alpha=0.6,
                       label=f"{case}: paper GPU, {unit_name}")
    left.set_ylabel("speedup, CPU time / GPU time (same work)")
    left.set_title("CPU / GPU, each of one run length", fontsize=9)
    right.set_ylabel("GPU time per step or per linear solve [s]")
    right.set_title("GPU time per step (per linear solve); the paper's\nonly where its step count is known",
                    fontsize=9)
    for axes in (left, right):
        axes.set_xscale("log")
        axes.set_yscale("log")
        axes.set_xlabel("DOF (the paper's count, elements × 24)")
        axes.grid(True, which="both", alpha=0.3)
        axes.legend(fontsize=6, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)
    figure.tight_layout()
    path = os.path.join(out, "speedup.png")
    figure.savefig(path + ".tmp.png", dpi=150)
    os.replace(path + ".tmp.png", path)
    plt.close(figure)
    return path


def parse_arguments(arguments):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--app", default="", help="the perishell executable (a CUDA build runs both backends)")
    parser.add_argument("--out", required=True, help="directory for speedup.csv, speedup.md, speedup.png")
    parser.add_argument("--cases", default="pressed,steel,prism,cylinder,glass",
                        help="comma-separated, of: " + ", ".join(CASES))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--cpu-threads", type=int, default=2)
    parser.add_argument("--cpu-steps", type=int, default=20, help="explicit steps on the CPU (0: the whole deck)")
    parser.add_argument("--gpu-steps", type=int, default=0, help="explicit steps on the GPU (0: the whole deck)")
    parser.add_argument("--long-run", type=float, default=30.0,
                        help="a point whose first run takes longer [s] is not repeated")
    parser.add_argument("--quick", action="store_true", help="only each case's coarsest grid")
    parser.add_argument("--spacing", type=float, default=0.0,
                        help="run each case at this grid spacing [m] only (no paper numbers; smoke tests)")
    parser.add_argument("--report-only", action="store_true",
                        help="measure nothing: rewrite speedup.md and speedup.png from OUT/speedup.csv")
    parser.add_argument("--append", action="store_true",
                        help="keep the other cases of OUT/speedup.csv (from an earlier run) in the tables")
    parser.add_argument("--machine", default="",
                        help="the machine, for the report (default: from /proc/cpuinfo and nvidia-smi)")
    options = parser.parse_args(arguments)
    options.cases = [c for c in options.cases.split(",") if c]
    unknown = [c for c in options.cases if c not in CASES]
    if unknown:
        parser.error(f"--cases: unknown case(s) {', '.join(unknown)}; known: {', '.join(CASES)}")
    for name in ("repeats", "cpu_threads"):
        if getattr(options, name) < 1:
            parser.error(f"--{name.replace('_', '-')}: must be at least 1")
    if options.spacing < 0 or not math.isfinite(options.spacing):
        parser.error("--spacing: must be a positive number of metres")
    for name in ("cpu_steps", "gpu_steps"):
        if getattr(options, name) < 0:
            parser.error(f"--{name.replace('_', '-')}: must be 0 or more")
    if not options.report_only and not os.access(options.app, os.X_OK):
        parser.error(f"--app: '{options.app}' is not an executable")
    return options


def describe_machine():
    cpu = "unknown CPU"
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as stream:
            names = re.findall(r"^model name\s*:\s*(.+)$", stream.read(), flags=re.M)
        if names:
            cpu = f"{names[0].strip()} ({len(names)} logical CPUs)"
    except OSError:
        pass
    try:
        gpu = subprocess.run(["nvidia-smi", "--query-gpu=name", "--format=csv,noheader"], capture_output=True,
                             text=True, timeout=30).stdout.strip().splitlines()
    except (OSError, subprocess.SubprocessError):
        gpu = []
    return f"Machine: {cpu}" + (f"; GPU: {gpu[0]}" if gpu else "; no GPU (the device backend is the host's)")


def record_run(out, options):
    """OUT/runs.txt: the machine and command of each run that wrote OUT (--append adds a line)."""
    path = os.path.join(out, "runs.txt")
    earlier = open(path, encoding="utf-8").read().splitlines() if options.append and os.path.exists(path) else []
    machine = options.machine or describe_machine()
    line = (f"{time.strftime('%Y-%m-%d')}, {machine}: `{' '.join(sys.argv)}`")
    runs = earlier + [line]
    with open(path + ".tmp", "w", encoding="utf-8") as stream:
        stream.write("\n".join(runs) + "\n")
    os.replace(path + ".tmp", path)
    return runs


def main(arguments):
    options = parse_arguments(arguments)
    os.makedirs(options.out, exist_ok=True)
    if options.report_only:
        runs = open(os.path.join(options.out, "runs.txt"), encoding="utf-8").read().splitlines()
        for path in write_outputs(options.out, load_previous(options.out), options, runs):
            print(path)
        return 0
    results = {key: entry for key, entry in load_previous(options.out).items() if key[0] not in options.cases} \
        if options.append else {}
    with tempfile.TemporaryDirectory(prefix="perishell-speedup-") as work:
        for case in options.cases:
            spec = CASES[case]
            grids = spec["grids"][:1] if options.quick else spec["grids"]
            if options.spacing:  # one grid outside the paper's tables
                grids = [(options.spacing, None, None, None, True)]
            for index, (spacing, paper_dof, _, _, on_cpu) in enumerate(grids):
                entry = {"spacing": spacing, "paper_dof": paper_dof}
                implicit = spec["kind"] == "implicit"
                split = not implicit and index == 0  # the phase table's grid
                if on_cpu:
                    entry["host"] = measure(options.app, case, spacing, "host", 1 if implicit else options.cpu_steps,
                                            options.cpu_threads, options.repeats, work, split, options.long_run)
                entry["device"] = measure(options.app, case, spacing, "device", 1 if implicit else options.gpu_steps,
                                          options.cpu_threads, options.repeats, work, split, options.long_run)
                results[(case, spacing)] = entry
    runs = record_run(options.out, options)
    for path in write_outputs(options.out, results, options, runs):
        print(path)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv[1:]))
    except SpeedupError as error:
        print(f"speedup: error: {error}", file=sys.stderr)
        sys.exit(1)
