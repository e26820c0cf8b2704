#!/usr/bin/env python3
"""Distributed explicit runs against rank count (docs/parallel.md): per-step time, halo
exchange time and bytes, parallel efficiency. Each configuration runs --repeats times as a
whole `mpirun -np R perishell run DECK --max-steps S --phase-times`; the table gives medians.
The step time is the run's "steps" phase (output and set-up excluded); the exchange time is
rank 0's, with a fence after each phase. Efficiency is t(1 rank) / (R t(R ranks)) at the same
threads per rank.

--spacing DX runs the deck on a grid of spacing DX [m] instead of its own (its `spacing:` line
replaced in a copy), for the halo bytes and exchange times against model size (1e5-1e7 nodes);
the node count is in the table.

usage: mpi_scaling.py --app PERISHELL --deck DECK [--ranks 1,2] [--threads 1] [--steps 200]
                      [--repeats 3] [--mpirun mpirun] [--out DIR] [--spacing DX] [--extra ARG ...]
"""
import argparse
import csv
import os
import re
import statistics
import subprocess
import sys


def run_once(args, ranks, threads, directory):
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), OMP_PROC_BIND="false",
               OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    command = [args.mpirun, "-np", str(ranks), "--oversubscribe", "--bind-to", "none", args.app, "run", args.deck,
               "--max-steps", str(args.steps), "--phase-times", "--output", directory] + args.extra
    result = subprocess.run(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if result.returncode != 0:
        sys.exit(f"mpi_scaling: {' '.join(command)} exited {result.returncode}:\n{result.stdout[-3000:]}")
    with open(os.path.join(directory, "timings.csv")) as handle:
        phases = {row["phase"]: float(row["seconds"]) for row in csv.DictReader(handle)}
    halo = re.search(r"halo exchange per step: (\d+) halo nodes x \d+ doubles = (\d+) bytes", result.stdout)
    nodes = re.search(r"explicit: (\d+) PD nodes, (\d+) bonds", result.stdout)
    return {"steps": phases["steps"], "exchange": phases.get("exchange", 0.0),
            "halo_nodes": int(halo.group(1)) if halo else 0, "halo_bytes": int(halo.group(2)) if halo else 0,
            "nodes": int(nodes.group(1)) if nodes else 0, "bonds": int(nodes.group(2)) if nodes else 0}


def deck_with_spacing(deck, spacing, directory):
    """A copy of the deck with its mesh spacing replaced."""
    with open(deck) as handle:
        text = handle.read()
    changed, count = re.subn(r"^(\s*spacing:\s*)[0-9.eE+-]+", lambda m: m.group(1) + repr(spacing), text, flags=re.M)
    if count != 1:
        sys.exit(f"mpi_scaling: {deck} has {count} 'spacing:' lines, not one")
    os.makedirs(directory, exist_ok=True)
    path = os.path.join(directory, f"spacing-{spacing:g}-" + os.path.basename(deck))
    with open(path, "w") as handle:
        handle.write(changed)
    return path


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--app", required=True)
    parser.add_argument("--deck", required=True)
    parser.add_argument("--ranks", default="1,2")
    parser.add_argument("--threads", default="1", help="OpenMP threads per rank (comma list)")
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--mpirun", default="mpirun")
    parser.add_argument("--out", default="/tmp/mpi_scaling")
    parser.add_argument("--spacing", type=float, default=None, help="grid spacing [m] replacing the deck's")
    parser.add_argument("--extra", nargs="*", default=[], help="more arguments for perishell run")
    args = parser.parse_args()
    if args.spacing is not None:
        args.deck = deck_with_spacing(args.deck, args.spacing, args.out)
    rows = []
    for threads in [int(t) for t in args.threads.split(",")]:
        base = None
        for ranks in [int(r) for r in args.ranks.split(",")]:
            samples = [run_once(args, ranks, threads, os.path.join(args.out, f"r{ranks}-t{threads}-{k}"))
                       for k in range(args.repeats)]
            step = statistics.median(s["steps"] for s in samples) / args.steps
            exchange = statistics.median(s["exchange"] for s in samples) / args.steps
            if base is None and ranks == 1:
                base = step
            efficiency = base / (ranks * step) if base else float("nan")
            rows.append((ranks, threads, step, exchange, samples[0]["halo_nodes"], samples[0]["halo_bytes"],
                         samples[0]["nodes"], efficiency))
            print(f"ranks {ranks} x {threads} threads: {1e3 * step:.3f} ms per step (exchange {1e3 * exchange:.3f} ms), "
                  f"{samples[0]['halo_bytes']} halo bytes per step", flush=True)
    print()
    print(f"{args.deck}, {args.steps} steps, median of {args.repeats}")
    print("| nodes | ranks | threads/rank | ms per step | exchange ms (rank 0) | halo nodes | halo kB per step | efficiency |")
    print("|---|---|---|---|---|---|---|---|")
    for ranks, threads, step, exchange, halo_nodes, halo_bytes, nodes, efficiency in rows:
        print(f"| {nodes} | {ranks} | {threads} | {1e3 * step:.3f} | {1e3 * exchange:.3f} | {halo_nodes} | "
              f"{halo_bytes / 1e3:.1f} | {efficiency:.2f} |")


if __name__ == "__main__":
    main()
