#!/usr/bin/env python3
"""What triangles cost against quads on the same nodes (docs/verification.md, "Triangles").

A flat clamped square plate under pressure, n x n cells, meshed as quads and as the same nodes
with every cell cut into two triangles (Gmsh files), run by `perishell run`:
  implicit  CCM, 2 increments, sparse Cholesky preconditioner;
  explicit  CCM, --steps steps, solver.shell-element one-point (the default: one-point quads,
            the explicit triangle) and mitc4 (stored K_l for quads and triangles).
Times come from the run's timings.csv (medians over --repeats runs): the implicit run's
element work (internal forces + tangent assembly) and whole solve (total less setup and
output), the explicit run's steps; each per node (and per increment or step).

  perf/triangle_cost.py --app build/openmp/apps/perishell --out OUT [--cells 100] [--steps 500]
                        [--repeats 3] [--backend host|device] [--solvers implicit,explicit]

Writes OUT/triangle_cost.md.
"""
import argparse
import csv
import os
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from shell_benchmarks import edge, grid, write_msh  # noqa: E402  (the Gmsh writer the benchmarks use)


def write_plate(path, n, triangles):
    """The unit square, n x n cells (quads, or each cut into two triangles across alternating
    diagonals); curves left/right/bottom/top."""
    nodes, quads, node = grid(n, n, lambda a, b: (a, b, 0.0))
    cells = []
    for j in range(n):
        for i in range(n):
            a, b, c, d = node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)
            if not triangles:
                cells.append((a, b, c, d))
            elif (i + j) % 2 == 0:
                cells += [(a, b, c), (a, c, d)]
            else:
                cells += [(a, b, d), (b, c, d)]
    write_msh(path, nodes, cells, {
        "bottom": (1, edge(node, [(i, 0) for i in range(n + 1)])),
        "right": (1, edge(node, [(n, j) for j in range(n + 1)])),
        "top": (1, edge(node, [(i, n) for i in range(n + 1)])),
        "left": (1, edge(node, [(0, j) for j in range(n + 1)]))})


def deck(mesh, n, solver):
    return f"""perishell:
  version: 1
  title: "triangle cost: clamped plate"
  mesh: {{generator: gmsh, file: {mesh}, spacing: {1.0 / n}}}
  material: {{young-modulus: 210.0e9, poisson-ratio: 0.3, density: 7850.0, thickness: 0.01}}
  zones: {{default: ccm}}
  supports:
    left: {{set: left, dofs: [ux, uy, uz, rx, ry, rz]}}
    right: {{set: right, dofs: [ux, uy, uz, rx, ry, rz]}}
    bottom: {{set: bottom, dofs: [ux, uy, uz, rx, ry, rz]}}
    top: {{set: top, dofs: [ux, uy, uz, rx, ry, rz]}}
  loads: {{q: {{type: pressure, value: 1000.0}}}}
  solver: {solver}
  output: {{directory: out, every: 0, history-every: 1}}
"""


def run(app, deck_path, backend):
    result = subprocess.run([app, "run", deck_path, "--backend", backend], capture_output=True, text=True,
                            env=dict(os.environ, OMP_PROC_BIND=os.environ.get("OMP_PROC_BIND", "false")))
    if result.returncode != 0:
        sys.exit(f"{deck_path}: exit {result.returncode}\n{result.stdout[-2000:]}{result.stderr[-2000:]}")
    with open(os.path.join(os.path.dirname(deck_path), "out", "timings.csv")) as f:
        return {row["phase"]: float(row["seconds"]) for row in csv.DictReader(f)}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--app", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--cells", type=int, default=100)
    parser.add_argument("--steps", type=int, default=500)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--backend", default="host", choices=["device", "host"])
    parser.add_argument("--solvers", default="implicit,explicit", help="which runs: implicit, explicit or both")
    args = parser.parse_args()
    n, nodes = args.cells, (args.cells + 1) ** 2
    implicit = "{type: implicit, increments: 2, preconditioner: cholesky}"
    explicit = lambda element: f"{{type: explicit, steps: {args.steps}, shell-element: {element}}}"
    runs = [("implicit", "quads", False, implicit), ("implicit", "triangles", True, implicit),
            ("explicit one-point", "quads", False, explicit("one-point")),
            ("explicit one-point", "triangles", True, explicit("one-point")),
            ("explicit mitc4", "quads", False, explicit("mitc4")),
            ("explicit mitc4", "triangles", True, explicit("mitc4"))]
    runs = [r for r in runs if r[0].split()[0] in args.solvers.split(",")]
    rows = []
    for solver, meshing, triangles, settings in runs:
        directory = os.path.join(args.out, f"{solver.replace(' ', '-')}-{meshing}")
        os.makedirs(directory, exist_ok=True)
        write_plate(os.path.join(directory, "mesh.msh"), n, triangles)
        deck_path = os.path.join(directory, "deck.yaml")
        with open(deck_path, "w") as f:
            f.write(deck("mesh.msh", n, settings))
        timings = [run(args.app, deck_path, args.backend) for _ in range(args.repeats)]
        median = lambda key: statistics.median(t.get(key, 0.0) for t in timings)
        if solver == "implicit":
            element = median("internal-forces") + median("assembly")
            solve = statistics.median(t["total"] - t["setup"] - t.get("output", 0.0) for t in timings)
            rows.append((solver, meshing, element / nodes * 1e6, solve / nodes * 1e6, "per node, 2 increments"))
        else:
            steps = median("steps")
            rows.append((solver, meshing, steps / nodes / args.steps * 1e9, None, "ns per node and step"))
        print(rows[-1], flush=True)
    with open(os.path.join(args.out, "triangle_cost.md"), "w") as f:
        f.write(f"backend {args.backend}, {n} x {n} cells ({nodes} nodes), median of {args.repeats} runs\n\n"
                "| run | mesh | element work | whole solve | unit |\n|---|---|---|---|---|\n")
        for solver, meshing, element, solve, unit in rows:
            f.write(f"| {solver} | {meshing} | {element:.3g} | {'-' if solve is None else f'{solve:.3g}'} | "
                    f"{'µs' if solve is not None else ''} {unit} |\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
