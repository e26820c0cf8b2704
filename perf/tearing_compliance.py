#!/usr/bin/env python3
"""The static energy release rate of the paper's tearing example 4.2.2, from our own model.

The deck apps/cases/steel_plate_4_2_2.yaml tears a pre-cracked steel plate by opposite
out-of-plane forces F on the two crack flanks. Under a static load the crack grows once
the energy release rate reaches G_c; by the compliance method (Irwin-Kies)

    G(F) = F^2 / (2 t) dC/da,  C = (w_left - w_right) / F,  a = the crack's total length,

so the load at which the crack starts to run statically is F_c = sqrt(2 t G_c / (dC/da)).
This script makes the example's deck implicit, linear (a small load, one increment, the
sparse Cholesky preconditioner), runs it with the pre-crack shortened and lengthened by
--step at each tip, the flank forces unchanged, reads the flanks' mean uz (history
`load-points`) and prints C(a), dC/da (central difference), G at the deck's full load and F_c.
Both runs with a changed crack length move whole node rows across the crack (1.75 mm grid).

  python3 perf/tearing_compliance.py --app build/openmp/apps/perishell --out OUT [--step 1.75e-3]
"""
import argparse
import csv
import math
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DECK = os.path.join(ROOT, "apps", "cases", "steel_plate_4_2_2.yaml")
PROBE_LOAD = 10.0  # N per flank: small enough for a linear response (opening ~0.03 mm)
FLANK_NODES = 17  # the deck's flank node sets: one node column along the 30 mm crack


def deck_values(text):
    """Crack start/end y, thickness, G_c, the flanks' nodal force and the full flank load."""
    start = re.search(r"start: \[([-0-9.e]+), ([-0-9.e]+), ([-0-9.e]+)\]", text)
    end = re.search(r"end: \[([-0-9.e]+), ([-0-9.e]+), ([-0-9.e]+)\]", text)
    thickness = float(re.search(r"thickness: ([0-9.e+-]+)", text).group(1))
    fracture_energy = float(re.search(r"fracture-energy: ([0-9.e+-]+)", text).group(1))
    nodal_force = float(re.search(r"lift-left-flank: .*vector: \[0\.0, 0\.0, ([0-9.e+-]+)\]", text).group(1))
    return start, end, thickness, fracture_energy, nodal_force


def implicit_deck(text, y_start, y_end, nodal_force, out_dir):
    """The example made static: pre-crack from y_start to y_end, flank forces scaled."""
    text = re.sub(r"(start: \[[-0-9.e]+, )[-0-9.e]+", lambda m: m.group(1) + repr(y_start), text, count=1)
    text = re.sub(r"(end: \[[-0-9.e]+, )[-0-9.e]+", lambda m: m.group(1) + repr(y_end), text, count=1)
    text = re.sub(r"(vector: \[0\.0, 0\.0, )(-?)[0-9.e+-]+\]", lambda m: m.group(1) + m.group(2) + repr(nodal_force) + "]",
                  text)
    text = re.sub(r", curve: ramp\}", "}", text)
    text = re.sub(r"\n  curves:\n    ramp: [^\n]*", "", text)
    solver = "  solver:\n    type: implicit\n    increments: 1\n    preconditioner: cholesky\n"
    text = re.sub(r"\n  solver:\n(    [^\n]*\n)+", "\n" + solver, text)
    text = re.sub(r"\n  output:\n(    [^\n]*\n?)+",
                  "\n  output:\n    directory: " + out_dir + "\n    history: [load-points]\n", text)
    return text


def opening(history_path):
    with open(history_path, encoding="utf-8") as stream:
        row = list(csv.DictReader(stream))[-1]
    return float(row["lift-left-flank-uz"]) - float(row["push-right-flank-uz"])


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--app", required=True, help="the perishell binary")
    parser.add_argument("--out", required=True, help="directory for the decks and runs")
    parser.add_argument("--step", type=float, default=1.75e-3, help="crack growth per tip [m] (default: one grid row)")
    args = parser.parse_args()
    if not (args.step > 0):
        sys.exit("tearing_compliance: --step must be positive")
    os.makedirs(args.out, exist_ok=True)
    with open(DECK, encoding="utf-8") as stream:
        text = stream.read()
    start, end, thickness, fracture_energy, nodal_force = deck_values(text)
    full_load = FLANK_NODES * nodal_force
    y0, y1 = float(start.group(2)), float(end.group(2))
    compliance = {}
    for grow in (-1, 0, 1):
        length = (y1 - y0) + 2 * grow * args.step
        name = "crack_%.2fmm" % (length * 1e3)
        run_dir = os.path.join(args.out, name)
        deck_path = os.path.join(args.out, name + ".yaml")
        with open(deck_path, "w", encoding="utf-8") as stream:
            stream.write(implicit_deck(text, y0 - grow * args.step, y1 + grow * args.step, PROBE_LOAD / FLANK_NODES, run_dir))
        result = subprocess.run([args.app, "run", deck_path], capture_output=True, text=True)
        if result.returncode != 0:
            sys.exit("tearing_compliance: %s failed:\n%s" % (deck_path, result.stdout[-2000:] + result.stderr[-2000:]))
        compliance[length] = opening(os.path.join(run_dir, "history.csv")) / PROBE_LOAD
        print("crack %.2f mm: C = %.5e m/N" % (length * 1e3, compliance[length]), flush=True)
    lengths = sorted(compliance)
    slope = (compliance[lengths[2]] - compliance[lengths[0]]) / (lengths[2] - lengths[0])
    energy_release = full_load ** 2 / (2 * thickness) * slope
    critical_load = math.sqrt(2 * thickness * fracture_energy / slope)
    print("dC/da = %.4e 1/N (central, a = %.2f mm)" % (slope, lengths[1] * 1e3))
    print("G at F = %.0f N: %.4g J/m^2 = %.3g G_c" % (full_load, energy_release, energy_release / fracture_energy))
    print("static load at which the crack runs: F_c = %.0f N (G_c = %.4g J/m^2, t = %.4g m)" %
          (critical_load, fracture_energy, thickness))
    print("static opening at F = %.0f N: %.4g mm" % (full_load, compliance[lengths[1]] * full_load * 1e3))


if __name__ == "__main__":
    main()
