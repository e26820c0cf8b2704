#!/usr/bin/env python3
"""Runs one deck on 1, 2 and 3 MPI ranks and asserts that every rank count writes the same
files: history.csv byte for byte, and every dataset of the field series (results.h5 and its
step files) bit for bit, read back through HDF5 (docs/parallel.md). Also asserts that the run
did something worth comparing: bonds broke (the history's broken-bonds column grows).

usage: compare_rank_counts.py --app PERISHELL --mpirun MPIRUN --deck DECK --work DIR [--ranks 1,2,3]
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


def run(app, mpirun, deck, ranks, directory):
    env = dict(os.environ, OMP_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    command = [mpirun, "-np", str(ranks), "--oversubscribe", "--bind-to", "none", app, "run", deck,
               "--output", directory]
    result = subprocess.run(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if result.returncode != 0:
        sys.exit(f"FAIL: {' '.join(command)} exited {result.returncode}:\n{result.stdout[-4000:]}")
    return result.stdout


def datasets(directory):
    """Every dataset of every .h5 file in directory: {(file, path): array}."""
    found = {}
    for path in sorted(glob.glob(os.path.join(directory, "*.h5"))):
        with h5py.File(path, "r") as handle:
            def visit(name, item):
                if isinstance(item, h5py.Dataset):
                    found[(os.path.basename(path), name)] = item[()]
            handle.visititems(visit)
    return found


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--app", required=True)
    parser.add_argument("--mpirun", required=True)
    parser.add_argument("--deck", required=True)
    parser.add_argument("--work", required=True)
    parser.add_argument("--ranks", default="1,2,3")
    args = parser.parse_args()
    counts = [int(r) for r in args.ranks.split(",")]
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work)
    outputs = {}
    for ranks in counts:
        directory = os.path.join(args.work, f"ranks-{ranks}")
        log = run(args.app, args.mpirun, args.deck, ranks, directory)
        outputs[ranks] = directory
        partition = [line for line in log.splitlines() if line.startswith("partition:") or "imbalance" in line]
        print(f"{ranks} rank(s): {' '.join(partition) if partition else 'one rank'}")

    reference = outputs[counts[0]]
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
    print(f"PASS: {args.deck} gives identical files on {args.ranks} ranks")


if __name__ == "__main__":
    main()
