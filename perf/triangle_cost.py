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


def write_plate(path, n, triangles):
    """The unit square, n x n cells; node (i, j) is 1 + j (n + 1) + i; curves left/right/bottom/top."""
    node = lambda i, j: 1 + j * (n + 1) + i
    sides = {"bottom": [(i, 0) for i in range(n + 1)], "right": [(n, j) for j in range(n + 1)],
             "top": [(i, n) for i in range(n + 1)], "left": [(0, j) for j in range(n + 1)]}
    lines = ["$MeshFormat", "4.1 0 8", "$EndMeshFormat", "$PhysicalNames", "5"]
    lines += [f'1 {tag} "{name}"' for tag, name in enumerate(sides, start=1)] + ['2 5 "plate"', "$EndPhysicalNames"]
    lines += ["$Entities", "0 4 1 0"] + [f"{tag} 0 0 0 0 0 0 1 {tag} 0" for tag in range(1, 5)]
    lines += ["1 0 0 0 1 1 0 1 5 0", "$EndEntities"]
    count = (n + 1) ** 2
    lines += ["$Nodes", f"1 {count} 1 {count}", f"2 1 0 {count}"] + [str(k) for k in range(1, count + 1)]
    lines += [f"{i / n:.12g} {j / n:.12g} 0" for j in range(n + 1) for i in range(n + 1)] + ["$EndNodes"]
    blocks, tag = [], 1
    for entity, points in enumerate(sides.values(), start=1):
        block = [f"1 {entity} 1 {n}"]
        for a, b in zip(points, points[1:]):
            block.append(f"{tag} {node(*a)} {node(*b)}")
            tag += 1
        blocks.append(block)
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
    block = [f"2 1 {2 if triangles else 3} {len(cells)}"]
    for cell in cells:
        block.append(" ".join(map(str, (tag,) + cell)))
        tag += 1
    blocks.append(block)
    lines += ["$Elements", f"{len(blocks)} {tag - 1} 1 {tag - 1}"]
    for block in blocks:
        lines += block
    lines += ["$EndElements"]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


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
