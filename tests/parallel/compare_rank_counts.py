#!/usr/bin/env python3
"""Runs one deck on 1, 2 and 3 MPI ranks and asserts that every rank count writes the same
files, read back through HDF5 (docs/parallel.md).

Explicit decks (default): history.csv byte for byte, and every dataset of the field series
(results.h5 and its step files) bit for bit; the run must have done something worth comparing:
bonds broke (the history's broken-bonds column grows).

Implicit decks (--relative-tolerance TOL): the per-rank preconditioner changes the Krylov
iterations, so the converged states agree to the Newton tolerance, not bit for bit: every
dataset and every history column of results (load factor, displacements, reactions, probes)
within TOL of the column's or dataset's largest magnitude; the solver's counters (Newton and
Krylov iterations, cuts, residual) are not compared, and the Krylov iterations are printed for
each rank count.

--max-krylov-growth G (implicit): the Krylov iterations over the run on any rank count may be
at most G times the first rank count's; overlap and the coarse space over the ranks keep them
there (docs/parallel.md, "Coupling the ranks' preconditioners").

--restart-at N: checkpoints across rank counts. Each rank count also runs the deck's first N
steps (increments), which ends in a checkpoint, and the next rank count in the list (the last
the first) continues it with --restart: the continued run's files are compared with the first
rank count's uninterrupted run as above (bit for bit, or within TOL).

--run-options "OPTS": more options for every run (e.g. "--exchange-overlap off").

usage: compare_rank_counts.py --app PERISHELL --mpirun MPIRUN --deck DECK --work DIR [--ranks 1,2,3]
                              [--relative-tolerance TOL] [--max-krylov-growth G] [--restart-at N]
                              [--run-options "OPTS"]
       compare_rank_counts.py --compare-only --deck DECK --work DIR [...]: compares the
                              directories DIR/ranks-N another machine wrote (a GPU run).
"""
import argparse
import csv
import glob
import os
import shutil
import subprocess
import sys

import h5py
import numpy as np


def linear_iterations(log):
    """The run summary's Krylov iterations ("linear iterations N"), or None."""
    for line in log.splitlines():
        fields = line.split()
        if fields[:2] == ["linear", "iterations"] and len(fields) > 2 and fields[2].isdigit():
            return int(fields[2])
    return None


def run(app, mpirun, deck, ranks, options):
    env = dict(os.environ, OMP_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    command = [mpirun, "-np", str(ranks), "--oversubscribe", "--bind-to", "none", app, "run", deck] + options
    result = subprocess.run(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if result.returncode != 0:
        sys.exit(f"FAIL: {' '.join(command)} exited {result.returncode}:\n{result.stdout[-4000:]}")
    return result.stdout


def datasets(directory):
    """Every dataset of every .h5 file in directory but the checkpoint: {(file, path): array}."""
    found = {}
    for path in sorted(glob.glob(os.path.join(directory, "*.h5"))):
        if os.path.basename(path) == "checkpoint.h5":
            continue
        with h5py.File(path, "r") as handle:
            def visit(name, item):
                if isinstance(item, h5py.Dataset):
                    found[(os.path.basename(path), name)] = item[()]
            handle.visititems(visit)
    return found


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--app")
    parser.add_argument("--mpirun")
    parser.add_argument("--compare-only", action="store_true")
    parser.add_argument("--deck", required=True)
    parser.add_argument("--work", required=True)
    parser.add_argument("--ranks", default="1,2,3")
    parser.add_argument("--relative-tolerance", type=float, default=None)
    parser.add_argument("--max-krylov-growth", type=float, default=None)
    parser.add_argument("--restart-at", type=int, default=None)
    parser.add_argument("--run-options", default="", help="more options for every `perishell run`, one string")
    args = parser.parse_args()
    counts = [int(r) for r in args.ranks.split(",")]
    if not args.compare_only:
        if not args.app or not args.mpirun:
            parser.error("--app and --mpirun are needed unless --compare-only")
        shutil.rmtree(args.work, ignore_errors=True)
        os.makedirs(args.work)
    outputs = {}
    krylov = {}  # from the run summaries; a history holds only the increments it records
    for ranks in counts:
        directory = os.path.join(args.work, f"ranks-{ranks}")
        outputs[ranks] = directory
        if args.compare_only:
            continue
        log = run(args.app, args.mpirun, args.deck, ranks, ["--output", directory] + args.run_options.split())
        krylov[ranks] = linear_iterations(log)
        partition = [line for line in log.splitlines() if line.startswith("partition:") or "imbalance" in line]
        print(f"{ranks} rank(s): {' '.join(partition) if partition else 'one rank'}")
    if args.restart_at is not None:
        for first, then in zip(counts, counts[1:] + counts[:1]):
            label = f"{first}-then-{then}"
            directory = os.path.join(args.work, f"ranks-{label}")
            outputs[label] = directory
            if args.compare_only:
                continue
            run(args.app, args.mpirun, args.deck, first, ["--output", directory, "--max-steps", str(args.restart_at)])
            log = run(args.app, args.mpirun, args.deck, then, ["--restart", directory])
            krylov[label] = linear_iterations(log)  # the summary counts from the run's start
            if "restart: continuing " not in log:
                sys.exit(f"FAIL: the run on {then} rank(s) did not continue the checkpoint of {first}:\n{log[-4000:]}")
            print(f"{first} rank(s) to step {args.restart_at}, continued on {then} rank(s)")
    counts = list(outputs)

    reference = outputs[counts[0]]
    if args.relative_tolerance is not None:
        compare_within(args, counts, outputs, krylov)
        return
    with open(os.path.join(reference, "history.csv")) as handle:
        rows = list(csv.DictReader(handle))
    broken = [float(row["broken-bonds"]) for row in rows]
    if not broken[-1] > 0:
        sys.exit(f"FAIL: no bond broke in {args.deck}; the comparison would not test fracture across ranks")
    print(f"history: {len(rows)} rows, {int(broken[-1])} broken bonds at the end")
    reference_history = open(os.path.join(reference, "history.csv"), "rb").read()
    reference_fields = datasets(reference)
    if not reference_fields:
        sys.exit(f"FAIL: no HDF5 datasets in {reference}")
    failures = []
    for ranks in counts[1:]:
        history = open(os.path.join(outputs[ranks], "history.csv"), "rb").read()
        if history != reference_history:
            failures.append(f"{ranks} ranks: history.csv differs from {counts[0]} rank(s)")
        fields = datasets(outputs[ranks])
        if sorted(fields) != sorted(reference_fields):
            failures.append(f"{ranks} ranks: the HDF5 files hold other datasets")
            continue
        for key, value in reference_fields.items():
            other = fields[key]
            if value.shape != other.shape or value.tobytes() != other.tobytes():
                difference = np.max(np.abs(value.astype(float) - other.astype(float))) if value.shape == other.shape else None
                failures.append(f"{ranks} ranks: {key[0]}:{key[1]} differs (max |difference| {difference})")
        print(f"{ranks} ranks: history.csv and {len(fields)} datasets compared with {counts[0]} rank(s)")
    if failures:
        sys.exit("FAIL:\n  " + "\n  ".join(failures))
    print(f"PASS: {args.deck} gives identical files on {args.ranks} ranks"
          + (" and continued across rank counts" if args.restart_at is not None else ""))


SOLVER_COUNTERS = {"increment", "newton-iterations", "linear-iterations", "cuts", "relative-residual"}


def history_columns(directory):
    with open(os.path.join(directory, "history.csv")) as handle:
        rows = list(csv.DictReader(handle))
    return {name: np.array([float(row[name]) for row in rows]) for name in rows[0]} if rows else {}


def relative_difference(value, other, scale=None):
    value, other = np.asarray(value, dtype=float), np.asarray(other, dtype=float)
    if not value.size:
        return 0.0
    scale = max(scale if scale is not None else np.max(np.abs(value)), 1e-300)
    return np.max(np.abs(value - other)) / scale


def column_family(name):
    """Columns measured against one scale: a component that is zero by symmetry (the tip's
    sideways displacement) is round-off, judged against the largest of its kind."""
    if name.startswith("reaction-"):
        return "reactions"
    component = name.rsplit("-", 1)[-1]
    if component in ("ux", "uy", "uz", "u"):
        return "translations"
    if component in ("rx", "ry", "rz"):
        return "rotations"
    return name


def compare_within(args, counts, outputs, summaries):
    reference = outputs[counts[0]]
    reference_history = history_columns(reference)
    reference_fields = datasets(reference)
    if not reference_history or not reference_fields:
        sys.exit(f"FAIL: {reference} holds no history rows or no HDF5 datasets")
    if not np.max(np.abs(reference_history["max-displacement"])) > 0:
        sys.exit(f"FAIL: nothing moved in {args.deck}; the comparison would test nothing")
    failures = []
    # The run summaries' counts; without them (--compare-only) the history's rows, which hold
    # only the increments the deck records.
    def recorded(history):
        return int(history["linear-iterations"].sum()) if "linear-iterations" in history else -1
    krylov = {counts[0]: summaries.get(counts[0]) or recorded(reference_history)}
    for ranks in counts[1:]:
        history = history_columns(outputs[ranks])
        krylov[ranks] = summaries.get(ranks) or recorded(history)
        if sorted(history) != sorted(reference_history) or len(history["load-factor"]) != len(
                reference_history["load-factor"]):
            failures.append(f"{ranks} ranks: history.csv has other columns or rows")
            continue
        worst = ("", 0.0)
        scales = {}
        for name, value in reference_history.items():
            family = column_family(name)
            scales[family] = max(scales.get(family, 0.0), float(np.max(np.abs(value))))
        for name, value in reference_history.items():
            if name in SOLVER_COUNTERS:
                continue
            difference = relative_difference(value, history[name], scales[column_family(name)])
            worst = max(worst, (name, difference), key=lambda item: item[1])
            if not difference <= args.relative_tolerance:
                failures.append(f"{ranks} ranks: history column {name} differs by {difference:.3e} (relative)")
        fields = datasets(outputs[ranks])
        if sorted(fields) != sorted(reference_fields):
            failures.append(f"{ranks} ranks: the HDF5 files hold other datasets")
            continue
        worstField = ("", 0.0)
        for key, value in reference_fields.items():
            other = fields[key]
            if value.shape != other.shape:
                failures.append(f"{ranks} ranks: {key[0]}:{key[1]} has shape {other.shape}, not {value.shape}")
                continue
            if not np.issubdtype(value.dtype, np.number):
                continue
            difference = relative_difference(value, other)
            worstField = max(worstField, (f"{key[0]}:{key[1]}", difference), key=lambda item: item[1])
            if not difference <= args.relative_tolerance:
                failures.append(f"{ranks} ranks: {key[0]}:{key[1]} differs by {difference:.3e} (relative)")
        print(f"{ranks} ranks: largest relative difference from {counts[0]} rank(s): history {worst[1]:.2e} "
              f"({worst[0]}), fields {worstField[1]:.2e} ({worstField[0]})")
    print("Krylov iterations over the run: " + ", ".join(f"{r} rank(s) {k}" for r, k in krylov.items()))
    if args.max_krylov_growth is not None:
        for ranks, count in krylov.items():
            if not count <= args.max_krylov_growth * krylov[counts[0]]:
                failures.append(f"{ranks} ranks: {count} Krylov iterations, more than {args.max_krylov_growth:g} x "
                                f"the {krylov[counts[0]]} on {counts[0]} rank(s)")
    if failures:
        sys.exit("FAIL:\n  " + "\n  ".join(failures))
    print(f"PASS: {args.deck} gives the same answers within {args.relative_tolerance:g} on {args.ranks} ranks"
          + (" and continued across rank counts" if args.restart_at is not None else ""))


if __name__ == "__main__":
    main()
