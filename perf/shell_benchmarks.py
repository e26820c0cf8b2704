#!/usr/bin/env python3
"""Implicit solver on the public nonlinear shell benchmarks of Sze, Liu & Lo (2004), "Popular
benchmark problems for geometric nonlinear analysis of shells", Finite Elements in Analysis
and Design 40: 3.3 the slit annular plate under a line force, 3.4 the hemispherical shell with
an 18 degree hole (quarter), 3.8 the hinged cylindrical roof under a central point force
(quarter, arc-length control through both limit points; §3.8 in the paper). Each
case is written as a Gmsh 4.1 mesh and a deck, then run by `perishell run` once per
preconditioner and Newton format (solver.newton); the table gives wall time, increments, cuts, Newton and Krylov iterations and
factorizations (medians over --repeats runs for the time).

  perf/shell_benchmarks.py --app build/openmp/apps/perishell --out OUT [--cases slit,hemisphere,roof]
                           [--preconditioners amg,cholesky,direct,cholesky@host,cholesky@device]
                           [--newton mixed,displacement]
                           [--repeats 3] [--backend host|device]

A preconditioner written NAME@PLACE also sets solver.factorization (host or device: where a
GPU run factors the tangent). Writes OUT/<case>/ (mesh, deck, runs) and OUT/shell_benchmarks.md.
"""
import argparse
import csv
import itertools
import math
import os
import re
import statistics
import subprocess
import sys
import time


def write_msh(path, nodes, quads, groups):
    """nodes: [(x, y, z)], 1-based quads [(a, b, c, d)] (or triangles (a, b, c), in any mix),
    groups: name -> (dim, [elements]) where a dim-1 element is a node pair and a dim-0 element a
    single node; every group but the surface "shell" needs at least one element."""
    names = list(groups)
    lines = ["$MeshFormat", "4.1 0 8", "$EndMeshFormat", "$PhysicalNames", str(len(names) + 1)]
    for tag, name in enumerate(names, start=1):
        lines.append(f'{groups[name][0]} {tag} "{name}"')
    lines += [f'2 {len(names) + 1} "shell"', "$EndPhysicalNames"]
    points = [(t, n) for t, n in enumerate(names, start=1) if groups[n][0] == 0]
    curves = [(t, n) for t, n in enumerate(names, start=1) if groups[n][0] == 1]
    lines += ["$Entities", f"{len(points)} {len(curves)} 1 0"]
    for tag, name in points:
        x, y, z = nodes[groups[name][1][0] - 1]
        lines.append(f"{tag} {x} {y} {z} 1 {tag}")
    for tag, name in curves:
        lines.append(f"{tag} 0 0 0 0 0 0 1 {tag} 0")
    lines.append(f"1 0 0 0 0 0 0 1 {len(names) + 1} 0")
    lines += ["$EndEntities", "$Nodes", f"1 {len(nodes)} 1 {len(nodes)}", f"2 1 0 {len(nodes)}"]
    lines += [str(k) for k in range(1, len(nodes) + 1)]
    lines += [f"{x:.12g} {y:.12g} {z:.12g}" for x, y, z in nodes]
    lines += ["$EndNodes"]
    blocks, tag = [], 1
    for entity, name in points + curves:
        dim, elements = groups[name]
        block = [f"{dim} {entity} {15 if dim == 0 else 1} {len(elements)}"]
        for element in elements:
            element = element if isinstance(element, tuple) else (element,)
            block.append(" ".join(map(str, (tag,) + element)))
            tag += 1
        blocks.append(block)
    for corners, gmsh_type in ((4, 3), (3, 2)):
        surface = [element for element in quads if len(element) == corners]
        if not surface:
            continue
        block = [f"2 1 {gmsh_type} {len(surface)}"]
        for element in surface:
            block.append(" ".join(map(str, (tag,) + tuple(element))))
            tag += 1
        blocks.append(block)
    lines += ["$Elements", f"{len(blocks)} {tag - 1} 1 {tag - 1}"]
    for block in blocks:
        lines += block
    lines += ["$EndElements"]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def grid(n1, n2, position):
    """(n1 + 1) x (n2 + 1) nodes at position(i / n1, j / n2); node (i, j) is 1 + j (n1 + 1) + i."""
    nodes = [position(i / n1, j / n2) for j in range(n2 + 1) for i in range(n1 + 1)]
    node = lambda i, j: 1 + j * (n1 + 1) + i
    quads = [(node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)) for j in range(n2) for i in range(n1)]
    return nodes, quads, node


def edge(node, indices):
    return [(node(*a), node(*b)) for a, b in zip(indices, indices[1:])]


def slit_plate(directory, scale):
    """Sze 3.3: R_i 6, R_o 10, h 0.03, E 21e6, nu 0; clamped at theta = 0, line force q_max 0.8
    per unit length in z at the other side of the slit; 10 x 80 at scale 1."""
    nr, nt = 10 * scale, 80 * scale
    nodes, quads, node = grid(nr, nt, lambda a, b: ((6 + 4 * a) * math.cos(2 * math.pi * b),
                                                     (6 + 4 * a) * math.sin(2 * math.pi * b), 0.0))
    write_msh(os.path.join(directory, "mesh.msh"), nodes, quads, {
        "clamped": (1, edge(node, [(i, 0) for i in range(nr + 1)])),
        "loaded": (1, edge(node, [(i, nt) for i in range(nr + 1)])),
        "A": (0, [node(0, nt)]), "B": (0, [node(nr, nt)])})
    return deck("Sze 3.3 slit annular plate", 21e6, 0.0, 0.03, """
  supports:
    clamp: {set: clamped, dofs: [ux, uy, uz, rx, ry, rz]}
  loads:
    line: {type: edge-traction, set: loaded, vector: [0.0, 0.0, 26.666666666667]}
    probeA: {type: point-force, set: A, vector: [0.0, 0.0, 0.0]}
    probeB: {type: point-force, set: B, vector: [0.0, 0.0, 0.0]}""", 20, 0.4 / scale)


def hemisphere(directory, scale, force=200.0, title="Sze 3.4 hemispherical shell", increments=20):
    """Sze 3.4: R 10, h 0.04, E 6.825e7, nu 0.3, 18 degree hole; quarter with symmetry planes,
    radial forces 200 (the full shell's 400, halved on the planes), pull at A, push at B;
    16 x 16 at scale 1. The MacNeal-Harder pinched hemisphere is the same shell under 2 (1 on
    each plane's point)."""
    n = 16 * scale
    psi0 = math.radians(18.0)
    nodes, quads, node = grid(n, n, lambda a, b: (
        10 * math.sin(psi0 + a * (math.pi / 2 - psi0)) * math.cos(b * math.pi / 2),
        10 * math.sin(psi0 + a * (math.pi / 2 - psi0)) * math.sin(b * math.pi / 2),
        10 * math.cos(psi0 + a * (math.pi / 2 - psi0))))
    write_msh(os.path.join(directory, "mesh.msh"), nodes, quads, {
        "y0": (1, edge(node, [(i, 0) for i in range(n + 1)])),
        "x0": (1, edge(node, [(i, n) for i in range(n + 1)])),
        "A": (0, [node(n, 0)]), "B": (0, [node(n, n)]), "pin": (0, [node(0, 0)])})
    return deck(title, 6.825e7, 0.3, 0.04, f"""
  supports:
    symmetryY: {{set: y0, dofs: [uy, rx, rz]}}
    symmetryX: {{set: x0, dofs: [ux, ry, rz]}}
    pin: {{set: pin, dofs: [uz]}}
  loads:
    pull: {{type: point-force, set: A, vector: [{force}, 0.0, 0.0]}}
    push: {{type: point-force, set: B, vector: [0.0, {-force}, 0.0]}}""", increments, 0.98 / scale)


def roof(directory, scale):
    """Sze 3.8 (the hinged roof; numbered 3.5 in our issues): R 2540, half length 254, half angle
    0.1 rad, h 12.7, E 3102.75, nu 0.3; straight edge hinged, curved edge free; quarter with
    symmetry planes, central force P_max 3000 / 4 = 750, arc-length control through both limit
    points to P_max."""
    n = 8 * scale
    nodes, quads, node = grid(n, n, lambda a, b: (254.0 * a, 2540 * math.sin(0.1 * b),
                                                  2540 * math.cos(0.1 * b) - 2540 * math.cos(0.1)))
    write_msh(os.path.join(directory, "mesh.msh"), nodes, quads, {
        "hinged": (1, edge(node, [(i, n) for i in range(n + 1)])),
        "x0": (1, edge(node, [(0, j) for j in range(n + 1)])),
        "y0": (1, edge(node, [(i, 0) for i in range(n + 1)])),
        "centre": (0, [node(0, 0)])})
    return deck("Sze 3.8 hinged cylindrical roof", 3102.75, 0.3, 12.7, """
  supports:
    hinge: {set: hinged, dofs: [ux, uy, uz]}
    symmetryX: {set: x0, dofs: [ux, ry, rz]}
    symmetryY: {set: y0, dofs: [uy, rx, rz]}
  loads:
    centre: {type: point-force, set: centre, vector: [0.0, 0.0, -750.0]}""", 20, 31.75 / scale,
                "control: arc-length, max-increments: 200")


# MacNeal & Harder (1985), "A proposed standard set of problems to test finite element accuracy",
# Finite Elements in Analysis and Design 1: 3-20: linear problems. Where the reference load
# bends the shell by more than ~1e-4 of its size, the load is scaled down (load_scale) so that
# the geometrically nonlinear solver answers the linear problem; the reported displacement is
# the probe's divided by load_scale. Smaller scales than 1e-3 reach the round-off floor of
# the total-form corotational force (displacements ~1e-10 of the coordinates).


def scordelis_lo(directory, scale, load_scale):
    """Scordelis-Lo roof: R 25, L 50, 80 degree arc, t 0.25, E 4.32e8, nu 0, self-weight 90 per
    unit area; ends on rigid diaphragms (uy = uz = 0), long edges free. Quarter (x to midspan,
    crown to free edge), 16 x 16 at scale 1. Reference: vertical deflection at the midspan of
    the free edge, 0.3024."""
    n = 16 * scale
    phi = math.radians(40.0)
    nodes, quads, node = grid(n, n, lambda a, b: (25.0 * a, 25.0 * math.sin(phi * b), 25.0 * math.cos(phi * b)))
    write_msh(os.path.join(directory, "mesh.msh"), nodes, quads, {
        "diaphragm": (1, edge(node, [(0, j) for j in range(n + 1)])),
        "midspan": (1, edge(node, [(n, j) for j in range(n + 1)])),
        "crown": (1, edge(node, [(i, 0) for i in range(n + 1)]))})
    return deck("MacNeal-Harder Scordelis-Lo roof", 4.32e8, 0.0, 0.25, f"""
  supports:
    diaphragm: {{set: diaphragm, dofs: [uy, uz]}}
    symmetryX: {{set: midspan, dofs: [ux, ry, rz]}}
    symmetryY: {{set: crown, dofs: [uy, rx, rz]}}
  loads:
    weight: {{type: pressure, vector: [0.0, 0.0, {-90.0 * load_scale}]}}""", 1, 25.0 / n,
                probes={"A": (25.0, 25.0 * math.sin(phi), 25.0 * math.cos(phi))})


def pinched_hemisphere(directory, scale, load_scale):
    """Pinched hemisphere with an 18 degree hole: Sze 3.4's quarter under radial forces +-2 at
    four points of the equator (1 on each plane's point). Reference: radial displacement at the
    loads, 0.094."""
    return hemisphere(directory, scale, force=load_scale, title="MacNeal-Harder pinched hemisphere", increments=1)


def pinched_cylinder(directory, scale, load_scale):
    """Pinched cylinder with rigid end diaphragms: R 300, L 600, t 3, E 3e6, nu 0.3, two
    opposite radial forces 1 at midspan; one eighth (x from a diaphragm to midspan, a quarter
    of the circumference), force 1/4, 16 x 16 at scale 1. Reference: radial displacement under
    the force, 1.8248e-5."""
    n = 16 * scale
    nodes, quads, node = grid(n, n, lambda a, b: (300.0 * a, 300.0 * math.sin(0.5 * math.pi * b),
                                                  300.0 * math.cos(0.5 * math.pi * b)))
    write_msh(os.path.join(directory, "mesh.msh"), nodes, quads, {
        "diaphragm": (1, edge(node, [(0, j) for j in range(n + 1)])),
        "midspan": (1, edge(node, [(n, j) for j in range(n + 1)])),
        "y0": (1, edge(node, [(i, 0) for i in range(n + 1)])),
        "z0": (1, edge(node, [(i, n) for i in range(n + 1)])),
        "load": (0, [node(n, 0)])})
    return deck("MacNeal-Harder pinched cylinder", 3e6, 0.3, 3.0, f"""
  supports:
    diaphragm: {{set: diaphragm, dofs: [uy, uz]}}
    symmetryX: {{set: midspan, dofs: [ux, ry, rz]}}
    symmetryY: {{set: y0, dofs: [uy, rx, rz]}}
    symmetryZ: {{set: z0, dofs: [uz, rx, ry]}}
  loads:
    pinch: {{type: point-force, set: load, vector: [0.0, 0.0, {-0.25 * load_scale}]}}""", 1, 300.0 / n)


def twisted_beam(direction):
    def case(directory, scale, load_scale):
        """Twisted beam: L 12, width 1.1, t 0.32, twisted 90 degrees root to tip, E 29e6,
        nu 0.22, clamped root, unit tip force spread consistently over the tip edge; 12 x 2 at
        scale 1. Reference tip deflection along the force: 5.424e-3 for a force along the root's
        normal (z), 1.754e-3 along the root's width (y)."""
        nx, ny = 12 * scale, 2 * scale
        nodes, quads, node = grid(nx, ny, lambda a, b: (
            12.0 * a, 1.1 * (b - 0.5) * math.cos(0.5 * math.pi * a), 1.1 * (b - 0.5) * math.sin(0.5 * math.pi * a)))
        write_msh(os.path.join(directory, "mesh.msh"), nodes, quads, {
            "root": (1, edge(node, [(0, j) for j in range(ny + 1)])),
            "tip": (1, edge(node, [(nx, j) for j in range(ny + 1)]))})
        traction = [0.0, 0.0, 0.0]
        traction["xyz".index(direction)] = load_scale / (1.1 * 0.32)  # unit force over the tip section
        return deck(f"MacNeal-Harder twisted beam, tip force along {direction}", 29e6, 0.22, 0.32, f"""
  supports:
    clamp: {{set: root, dofs: [ux, uy, uz, rx, ry, rz]}}
  loads:
    tip: {{type: edge-traction, set: tip, vector: {traction}}}""", 1, 1.0 / scale, probes={"tip": (12.0, 0.0, 0.0)})
    return case


def deck(title, young, poisson, thickness, actions, increments, spacing, control="control: load", probes=None):
    probe_text = "" if not probes else ", probes: {" + ", ".join(
        f"{name}: [{x:.12g}, {y:.12g}, {z:.12g}]" for name, (x, y, z) in probes.items()) + "}"
    return f"""perishell:
  version: 1
  title: "{title}"
  mesh: {{generator: gmsh, file: mesh.msh, spacing: {spacing}}}
  material: {{young-modulus: {young}, poisson-ratio: {poisson}, density: 1.0, thickness: {thickness}}}
  zones: {{default: ccm}}{actions}
  solver: {{type: implicit, increments: {increments}, {control}, preconditioner: PRECONDITIONER, newton: NEWTON}}
  output: {{directory: out, every: 0, history-every: 1, history: [load-points]{probe_text}}}
"""


CASES = {"slit": slit_plate, "hemisphere": hemisphere, "roof": roof}
# name: (case, history column, sign, reference, load scale); the measured value is
# sign * column / load scale.
LINEAR_CASES = {
    "scordelis-lo": (scordelis_lo, "A-uz", -1.0, 0.3024, 1e-3),
    "pinched-hemisphere": (pinched_hemisphere, "pull-ux", 1.0, 0.094, 1e-3),
    "pinched-cylinder": (pinched_cylinder, "pinch-uz", -1.0, 1.8248e-5, 1.0),
    "twisted-beam-z": (twisted_beam("z"), "tip-uz", 1.0, 5.424e-3, 1e-3),
    "twisted-beam-y": (twisted_beam("y"), "tip-uy", 1.0, 1.754e-3, 1e-3),
}


def run(app, deck_path, backend, log_path):
    start = time.perf_counter()
    result = subprocess.run([app, "run", deck_path, "--backend", backend], capture_output=True, text=True,
                            env=dict(os.environ, OMP_PROC_BIND=os.environ.get("OMP_PROC_BIND", "false")))
    seconds = time.perf_counter() - start
    with open(log_path, "w") as f:
        f.write(result.stdout + result.stderr)
    text = result.stdout + result.stderr
    number = lambda pattern: (re.search(pattern, text) or [None, "-"])[1]
    return {"status": result.returncode, "seconds": seconds,
            "increments": number(r"increments +([0-9]+(?: of [0-9]+)?) \("),
            "cuts": number(r"increments +[0-9 of]+\(([0-9]+) cuts"),
            "newton": number(r"Newton iterations +([0-9]+)"),
            "krylov": number(r"linear iterations +([0-9]+)"),
            "factorizations": number(r"\(([0-9]+) factorizations[,)]"),
            "builds": number(r"\(([0-9]+) AMG builds?\)"),
            "max_u": number(r"max displacement +([0-9.e+-]+) m"),
            "limit": "yes" if "tangent             lost positive definiteness" in text else "no",
            "error": "" if result.returncode == 0 else text.strip().splitlines()[-1][:160]}


def last_history_value(output_directory, column):
    with open(os.path.join(output_directory, "history.csv")) as f:
        rows = list(csv.reader(f))
    return float(rows[-1][rows[0].index(column)])


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--app", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--cases", default="slit,hemisphere,roof")
    parser.add_argument("--preconditioners", default="amg,cholesky,direct")
    parser.add_argument("--newton", default="mixed", help="Newton formats to run: mixed, displacement or both")
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--scale", type=int, default=1, help="mesh refinement factor")
    parser.add_argument("--backend", default="device", choices=["device", "host"])
    args = parser.parse_args()
    rows = []
    for case in args.cases.split(","):
        directory = os.path.join(args.out, case)
        os.makedirs(directory, exist_ok=True)
        linear = LINEAR_CASES.get(case)
        template = linear[0](directory, args.scale, linear[4]) if linear else CASES[case](directory, args.scale)
        for preconditioner, newton in itertools.product(args.preconditioners.split(","), args.newton.split(",")):
            name = f"{preconditioner.replace('@', '-')}-{newton}"
            deck_path = os.path.join(directory, f"{name}.yaml")
            kind, _, place = preconditioner.partition("@")
            setting = kind + (f", factorization: {place}" if place else "")
            with open(deck_path, "w") as f:
                f.write(template.replace("PRECONDITIONER", setting).replace("NEWTON", newton).replace(
                    "directory: out", f"directory: out-{name}"))
            runs = [run(args.app, deck_path, args.backend, os.path.join(directory, f"{name}-{r}.log"))
                    for r in range(args.repeats)]
            result = dict(runs[-1], seconds=statistics.median(r["seconds"] for r in runs), value="-", relative="-")
            if linear and result["status"] == 0:
                value = linear[2] * last_history_value(os.path.join(directory, f"out-{name}"), linear[1]) / linear[4]
                result.update(value=f"{value:.5g}", relative=f"{value / linear[3]:.4f}")
            rows.append((case, preconditioner, newton, result))
            print(f"{case:11s} {preconditioner:9s} {newton:12s} {result['seconds']:8.2f} s  exit {result['status']}  "
                  f"increments {result['increments']}  cuts {result['cuts']}  Newton {result['newton']}  "
                  f"Krylov {result['krylov']}  factorizations {result['factorizations']}  "
                  f"AMG builds {result['builds']}  max |u| {result['max_u']}  limit point {result['limit']}"
                  + (f"  value {result['value']} (ours/reference {result['relative']})" if linear else "")
                  + (f"  ({result['error']})" if result["error"] else ""), flush=True)
    with open(os.path.join(args.out, "shell_benchmarks.md"), "w") as f:
        f.write(f"backend {args.backend}, scale {args.scale}, median of {args.repeats} run(s)\n\n"
                "| case | preconditioner | Newton format | exit | wall s | increments | cuts | Newton | Krylov | factorizations |"
                " AMG builds | max abs u | limit point | linear value | ours / reference |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n")
        for case, preconditioner, newton, r in rows:
            f.write(f"| {case} | {preconditioner} | {newton} | {r['status']} | {r['seconds']:.2f} | {r['increments']} | "
                    f"{r['cuts']} | {r['newton']} | {r['krylov']} | {r['factorizations']} | {r['builds']} | "
                    f"{r['max_u']} | {r['limit']} | {r['value']} | {r['relative']} |\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
