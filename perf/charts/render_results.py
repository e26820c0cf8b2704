#!/usr/bin/env python3
"""Render results of `perishell run` to PNG.

  damage   nodal field snapshots from the XDMF time series (io/xdmf_writer.hpp)
  history  columns of the CSV history (io/csv_history.hpp) against one another

Needs numpy, matplotlib and h5py (Debian: python3-numpy python3-matplotlib python3-h5py).
Errors (missing file, field or column, bad option) print one line and exit with status 1.
See perf/charts/README.md for examples.
"""
import argparse
import csv
import math
import os
import sys
import xml.etree.ElementTree as ElementTree

PROGRAM = "render_results"


class RenderError(Exception):
    """Bad input: the message names the file, field or column and the reason."""


try:
    import numpy as np
    import matplotlib

    matplotlib.use("Agg")  # files only; no display on the build machines
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from matplotlib.tri import Triangulation
except ImportError as missing:
    sys.exit(f"{PROGRAM}: error: {missing}; run with a python3 that has numpy and matplotlib "
             "(Debian's /usr/bin/python3 with python3-matplotlib python3-h5py)")


# ---------------------------------------------------------------------------------------------
# XDMF time series
# ---------------------------------------------------------------------------------------------

class Step:
    """One Uniform grid of the Temporal collection: its time and where its data live."""

    def __init__(self, index, time, topology, geometry, fields):
        self.index = index
        self.time = time
        self.topology = topology  # (h5 path, dataset)
        self.geometry = geometry  # (h5 path, dataset)
        self.fields = fields      # name -> (h5 path, dataset, components)


def hdf_reference(data_item, directory, context):
    """'file.h5:/dataset' of an HDF DataItem, the file resolved against the .xmf's directory."""
    if data_item is None or data_item.get("Format", "HDF") != "HDF":
        raise RenderError(f"{context}: expected an HDF DataItem")
    file_name, separator, dataset = (data_item.text or "").strip().rpartition(":")
    if not separator or not file_name or not dataset:
        raise RenderError(f"{context}: DataItem '{data_item.text}' is not of the form file.h5:/dataset")
    return os.path.join(directory, file_name), dataset


def read_xdmf_steps(xdmf_path):
    if not os.path.isfile(xdmf_path):
        raise RenderError(f"{xdmf_path}: no such file")
    try:
        root = ElementTree.parse(xdmf_path).getroot()
    except ElementTree.ParseError as error:
        raise RenderError(f"{xdmf_path}: not valid XML ({error})") from None
    directory = os.path.dirname(os.path.abspath(xdmf_path))
    collection = root.find("Domain/Grid")
    if collection is None:
        raise RenderError(f"{xdmf_path}: no Domain/Grid element")
    grids = collection.findall("Grid") if collection.get("GridType") == "Collection" else [collection]
    steps = []
    for index, grid in enumerate(grids):
        context = f"{xdmf_path}: grid '{grid.get('Name', index)}'"
        time_element = grid.find("Time")
        try:
            time = float(time_element.get("Value")) if time_element is not None else 0.0
        except (TypeError, ValueError):
            raise RenderError(f"{context}: Time Value '{time_element.get('Value')}' is not a number") from None
        topology = grid.find("Topology")
        if topology is None or topology.get("TopologyType") != "Quadrilateral":
            raise RenderError(f"{context}: expected a Quadrilateral Topology")
        fields = {}
        for attribute in grid.findall("Attribute"):
            name = attribute.get("Name")
            if attribute.get("Center", "Node") != "Node":
                continue  # only nodal fields are written; anything else is not ours to draw
            components = 3 if attribute.get("AttributeType") == "Vector" else 1
            fields[name] = hdf_reference(attribute.find("DataItem"), directory,
                                         f"{context} attribute '{name}'") + (components,)
        steps.append(Step(index, time,
                          hdf_reference(topology.find("DataItem"), directory, f"{context} Topology"),
                          hdf_reference(grid.find("Geometry/DataItem"), directory, f"{context} Geometry"),
                          fields))
    if not steps:
        raise RenderError(f"{xdmf_path}: lists no steps")
    return steps


def read_dataset(reference):
    try:
        import h5py  # here, so that 'history' works without h5py
    except ImportError:
        raise RenderError("reading .h5 files needs h5py (Debian: python3-h5py, /usr/bin/python3)") from None

    path, dataset = reference[0], reference[1]
    if not os.path.isfile(path):
        raise RenderError(f"{path}: no such file (listed in the .xmf)")
    try:
        with h5py.File(path, "r") as file:
            if dataset not in file:
                raise RenderError(f"{path}: no dataset '{dataset}'")
            return np.asarray(file[dataset][()])
    except OSError as error:
        raise RenderError(f"{path}: cannot read ({error})") from None


def pick_steps(steps, requested_times):
    """The step closest to each requested time [s], in the requested order, repeats dropped.

    Default: three times evenly spread over the run, ending at the last step (the first step
    is usually the undamaged start and tells little)."""
    times = np.array([step.time for step in steps])
    if requested_times is None:
        start, end = times[0], times[-1]
        requested_times = [start + (end - start) * k / 3.0 for k in (1, 2, 3)]
    picked = []
    for time in requested_times:
        step = steps[int(np.argmin(np.abs(times - time)))]
        if step not in picked:
            picked.append(step)
    return picked


AXIS_INDEX = {"x": 0, "y": 1, "z": 2}


def projection_axes(coordinates, view):
    """The two in-plane coordinate indices and the depth index for the chosen view."""
    if view == "auto":
        extents = coordinates.max(axis=0) - coordinates.min(axis=0)
        depth = int(np.argmin(extents))
        plane = [axis for axis in range(3) if axis != depth]
        return plane[0], plane[1], depth
    first, second = AXIS_INDEX[view[0]], AXIS_INDEX[view[1]]
    return first, second, 3 - first - second


class Snapshot:
    def __init__(self, time, axis_names, points, depth, quads, values):
        self.time = time
        self.axis_names = axis_names  # the two in-plane coordinates, e.g. ("x", "y")
        self.points = points  # nodes x 2, projected
        self.depth = depth    # nodes, the dropped coordinate (draw order)
        self.quads = quads    # elements x 4
        self.values = values  # nodes


def load_snapshot(step, field, mesh, deformed_scale, view):
    if field not in step.fields:
        raise RenderError(f"step {step.index} (t = {step.time:g} s) has no field '{field}'; "
                          f"it has: {', '.join(sorted(step.fields)) or 'none'}")
    reference = step.fields[field]
    coordinates, quads = mesh
    values = read_dataset(reference)
    if reference[2] != 1:  # a vector field (displacement, velocity): its magnitude
        values = np.linalg.norm(values.reshape(-1, reference[2]), axis=1)
    values = values.reshape(-1)
    if values.shape[0] != coordinates.shape[0]:
        raise RenderError(f"{reference[0]}:{reference[1]} has {values.shape[0]} values for "
                          f"{coordinates.shape[0]} nodes")
    if deformed_scale is not None:
        if "displacement" not in step.fields:
            raise RenderError(f"--deformed: step {step.index} (t = {step.time:g} s) has no "
                              f"'displacement' field; it has: {', '.join(sorted(step.fields))}")
        displacement = read_dataset(step.fields["displacement"]).reshape(coordinates.shape)
        coordinates = coordinates + deformed_scale * displacement
    first, second, depth = projection_axes(coordinates, view)
    return Snapshot(step.time, ("xyz"[first], "xyz"[second]), coordinates[:, [first, second]], coordinates[:, depth], quads, values)


def draw_snapshot(axes, snapshot, shading, vmin, vmax, cmap):
    """Quads drawn back to front along the dropped axis, so curved shells read right."""
    quads = snapshot.quads[np.argsort(snapshot.depth[snapshot.quads].mean(axis=1), kind="stable")]
    if shading == "flat":
        artist = PolyCollection(snapshot.points[quads], array=snapshot.values[quads].mean(axis=1),
                                cmap=cmap, edgecolors="face", linewidths=0.05)
        artist.set_clim(vmin, vmax)
        axes.add_collection(artist)
        axes.autoscale_view()
    else:
        # Each quad split along its 0-2 diagonal; gouraud interpolates the nodal values.
        triangles = np.stack([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]], axis=1).reshape(-1, 3)
        triangulation = Triangulation(snapshot.points[:, 0], snapshot.points[:, 1], triangles)
        artist = axes.tripcolor(triangulation, snapshot.values, shading="gouraud", cmap=cmap,
                                vmin=vmin, vmax=vmax)
    axes.set_aspect("equal")
    axes.set_xlabel(f"{snapshot.axis_names[0]} [m]")
    axes.set_ylabel(f"{snapshot.axis_names[1]} [m]")
    axes.set_title(f"t = {snapshot.time * 1e6:.3f} µs")
    return artist


def colour_range(field, snapshots, vmin, vmax):
    if field == "damage":
        low, high = 0.0, 1.0
    else:
        finite = np.concatenate([s.values[np.isfinite(s.values)] for s in snapshots])
        low, high = (finite.min(), finite.max()) if finite.size else (0.0, 1.0)
    low = low if vmin is None else vmin
    high = high if vmax is None else vmax
    if not low < high:
        high = low + 1.0  # a constant field still gets a colour bar
    return low, high


def figure_size(snapshot, panels):
    width = np.ptp(snapshot.points[:, 0]) or 1.0
    height = np.ptp(snapshot.points[:, 1]) or 1.0
    panel_width = 5.0
    panel_height = min(max(panel_width * height / width, 1.5), 8.0) + 1.0  # + title
    return panel_width * panels + 1.2, panel_height  # + colour bar


def run_damage(options):
    steps = read_xdmf_steps(options.xdmf)
    picked = pick_steps(steps, options.times)
    mesh_step = picked[0]
    coordinates = read_dataset(mesh_step.geometry).reshape(-1, 3).astype(float)
    quads = read_dataset(mesh_step.topology).reshape(-1, 4).astype(np.int64)
    if quads.size and (quads.min() < 0 or quads.max() >= coordinates.shape[0]):
        raise RenderError(f"{mesh_step.topology[0]}: topology refers to nodes outside 0..{coordinates.shape[0] - 1}")
    snapshots = [load_snapshot(step, options.field, (coordinates, quads), options.deformed, options.view)
                 for step in picked]
    vmin, vmax = colour_range(options.field, snapshots, options.vmin, options.vmax)
    label = options.field + (f" (deformed × {options.deformed:g})" if options.deformed is not None else "")
    prefix = options.out or os.path.splitext(options.xdmf)[0]
    if os.path.dirname(prefix):
        os.makedirs(os.path.dirname(prefix), exist_ok=True)
    written = []

    for snapshot in snapshots:
        figure, axes = plt.subplots(figsize=figure_size(snapshot, 1), constrained_layout=True)
        artist = draw_snapshot(axes, snapshot, options.shading, vmin, vmax, options.cmap)
        axes.set_title(f"{label} at t = {snapshot.time * 1e6:.3f} µs")
        figure.colorbar(artist, ax=axes, label=options.field, shrink=0.9)
        path = f"{prefix}_{options.field}_{round(snapshot.time * 1e9)}ns.png"
        figure.savefig(path, dpi=options.dpi, bbox_inches="tight")
        plt.close(figure)
        written.append(path)

    if len(snapshots) > 1:
        figure, panels = plt.subplots(1, len(snapshots), figsize=figure_size(snapshots[0], len(snapshots)),
                                      constrained_layout=True, squeeze=False)
        for axes, snapshot in zip(panels[0], snapshots):
            artist = draw_snapshot(axes, snapshot, options.shading, vmin, vmax, options.cmap)
        figure.suptitle(label)
        figure.colorbar(artist, ax=list(panels[0]), label=options.field, shrink=0.9)
        path = f"{prefix}_{options.field}_panel.png"
        figure.savefig(path, dpi=options.dpi, bbox_inches="tight")
        plt.close(figure)
        written.append(path)
    return written


# ---------------------------------------------------------------------------------------------
# CSV history
# ---------------------------------------------------------------------------------------------

def read_history(csv_path):
    """Column name -> numpy array. 'nan', 'inf', '-inf' read as such (csv_history.hpp)."""
    if not os.path.isfile(csv_path):
        raise RenderError(f"{csv_path}: no such file")
    with open(csv_path, newline="") as file:
        rows = list(csv.reader(file))
    if not rows or not rows[0]:
        raise RenderError(f"{csv_path}: empty (no header line)")
    names = rows[0]
    values = []
    for line_number, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        if len(row) != len(names):
            raise RenderError(f"{csv_path}:{line_number}: {len(row)} values, the header has {len(names)} columns")
        try:
            values.append([float(value) for value in row])
        except ValueError as error:
            raise RenderError(f"{csv_path}:{line_number}: {error}") from None
    if not values:
        raise RenderError(f"{csv_path}: no rows below the header")
    table = np.array(values)
    return {name: table[:, column] for column, name in enumerate(names)}


def find_column(columns, name, csv_path):
    """Exact column name, else the name without its unit ('time' finds 'time [s]')."""
    if name in columns:
        return name
    matches = [column for column in columns if column.split(" [")[0].strip() == name.strip()]
    if len(matches) == 1:
        return matches[0]
    reason = "is ambiguous" if matches else "is not a column"
    raise RenderError(f"{csv_path}: '{name}' {reason}; columns: {', '.join(columns)}")


def evaluate_expression(columns, expression, csv_path):
    """NAME, NAME-NAME or NAME+NAME; nothing else. Names may contain '-' themselves
    ('left-flank-uz-right-flank-uz'), so every '+'/'-' is tried as the operator and exactly
    one split must name two columns."""
    try:
        name = find_column(columns, expression, csv_path)
        return name, columns[name]
    except RenderError:
        pass  # not one column: try NAME-NAME / NAME+NAME
    candidates = []
    for position, character in enumerate(expression):
        if character not in "+-":
            continue
        left, right = expression[:position].strip(), expression[position + 1:].strip()
        try:
            left_name, right_name = find_column(columns, left, csv_path), find_column(columns, right, csv_path)
        except RenderError:
            continue
        candidates.append((left_name, character, right_name))
    if not candidates:
        raise RenderError(f"{csv_path}: '{expression}' is neither a column nor NAME-NAME / NAME+NAME of columns; "
                          f"columns: {', '.join(columns)}")
    if len(candidates) > 1:
        readings = "; ".join(f"'{a}' {op} '{b}'" for a, op, b in candidates)
        raise RenderError(f"'{expression}' can be read more than one way ({readings}); add spaces around the operator")
    left_name, operator, right_name = candidates[0]
    values = columns[left_name] - columns[right_name] if operator == "-" else columns[left_name] + columns[right_name]
    return f"{left_name} {operator} {right_name}", values


def run_history(options):
    columns = read_history(options.csv)
    x_name = find_column(columns, options.x, options.csv)
    series = [(name, columns[name]) for name in (find_column(columns, y, options.csv) for y in options.y)]
    series += [evaluate_expression(columns, expression, options.csv) for expression in options.y_expr]
    if not series:
        raise RenderError("history: give at least one --y column or --y-expr")
    if options.labels and len(options.labels) != len(series):
        raise RenderError(f"--labels: {len(options.labels)} labels for {len(series)} curves")
    if len(options.hline_label) > len(options.hline):
        raise RenderError(f"--hline-label: {len(options.hline_label)} labels for {len(options.hline)} --hline values")

    figure, axes = plt.subplots(figsize=(7.0, 4.5), constrained_layout=True)
    x = columns[x_name] * options.x_scale
    for number, (name, values) in enumerate(series):
        label = options.labels[number] if options.labels else name
        axes.plot(x, values * options.y_scale, marker="." if len(x) <= 60 else None, label=label)
    for number, value in enumerate(options.hline):
        label = options.hline_label[number] if number < len(options.hline_label) else f"{value:g}"
        axes.axhline(value * options.y_scale, color="0.3", linestyle="--", linewidth=1.0, label=label)

    def default_label(name, scale):
        return name if scale == 1.0 else f"{name} × {scale:g}"

    axes.set_xlabel(options.xlabel or default_label(x_name, options.x_scale))
    axes.set_ylabel(options.ylabel or default_label(series[0][0] if len(series) == 1 else "value", options.y_scale))
    if options.title:
        axes.set_title(options.title)
    if options.y_log:
        axes.set_yscale("log")
    if len(series) > 1 or options.hline:
        axes.legend()
    axes.grid(True, linewidth=0.3)
    out = options.out or os.path.splitext(options.csv)[0] + ".png"
    if os.path.dirname(out):
        os.makedirs(os.path.dirname(out), exist_ok=True)
    figure.savefig(out, dpi=options.dpi, bbox_inches="tight")
    plt.close(figure)
    return [out]


# ---------------------------------------------------------------------------------------------
# Command line
# ---------------------------------------------------------------------------------------------

class ArgumentParser(argparse.ArgumentParser):
    def error(self, message):
        self.print_usage(sys.stderr)
        self.exit(1, f"{PROGRAM}: error: {message}\n")


def finite_number(text):
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"'{text}' is not finite")
    return value


def parse_arguments(arguments):
    parser = ArgumentParser(prog=PROGRAM, description=__doc__.split("\n\n")[0],
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True, parser_class=ArgumentParser)

    damage = commands.add_parser("damage", help="nodal field snapshots from an XDMF time series")
    damage.add_argument("xdmf", help="the <base>.xmf written by perishell")
    damage.add_argument("--field", default="damage", help="scalar nodal field (default: damage)")
    damage.add_argument("--times", type=finite_number, nargs="+", metavar="T",
                        help="times [s]; the closest output steps are drawn "
                             "(default: 3 evenly spread, the last included)")
    damage.add_argument("--out", metavar="PREFIX",
                        help="writes PREFIX_<field>_<t in ns>ns.png and PREFIX_<field>_panel.png "
                             "(default: the .xmf path without .xmf)")
    damage.add_argument("--deformed", type=finite_number, metavar="SCALE",
                        help="draw at coordinates + SCALE × 'displacement'")
    damage.add_argument("--view", choices=["xy", "xz", "yz", "auto"], default="auto",
                        help="projection plane (auto: drop the coordinate of smallest extent)")
    damage.add_argument("--shading", choices=["gouraud", "flat"], default="gouraud",
                        help="gouraud: nodal values interpolated; flat: one colour per quad, the mean")
    damage.add_argument("--vmin", type=finite_number, help="colour range low (damage: 0, else the data's)")
    damage.add_argument("--vmax", type=finite_number, help="colour range high (damage: 1, else the data's)")
    damage.add_argument("--cmap", default="inferno", help="matplotlib colour map (default: inferno)")
    damage.add_argument("--dpi", type=int, default=150)
    damage.set_defaults(handler=run_damage)

    history = commands.add_parser("history", help="columns of a CSV history against one another")
    history.add_argument("csv", help="the history .csv written by perishell")
    history.add_argument("--x", default="time", help="x column (default: time); 'time' finds 'time [s]'")
    history.add_argument("--y", nargs="+", action="extend", default=[], metavar="COLUMN",
                         help="y column(s); repeatable")
    history.add_argument("--y-expr", nargs="+", action="extend", default=[], metavar="EXPR",
                         help="NAME, NAME-NAME or NAME+NAME of columns, e.g. 'left-flank-uz - right-flank-uz'")
    history.add_argument("--labels", nargs="+", metavar="TEXT", help="legend labels, one per curve")
    history.add_argument("--hline", type=finite_number, action="append", default=[], metavar="VALUE",
                         help="horizontal reference line in the y column's units (scaled by --y-scale); repeatable")
    history.add_argument("--hline-label", action="append", default=[], metavar="TEXT",
                         help="label of the matching --hline")
    history.add_argument("--x-scale", type=finite_number, default=1.0, help="x multiplier, e.g. 1e6 for s -> µs")
    history.add_argument("--y-scale", type=finite_number, default=1.0, help="y multiplier")
    history.add_argument("--xlabel")
    history.add_argument("--ylabel")
    history.add_argument("--title")
    history.add_argument("--y-log", action="store_true", help="logarithmic y axis")
    history.add_argument("--out", help="PNG path (default: the .csv path with .png)")
    history.add_argument("--dpi", type=int, default=150)
    history.set_defaults(handler=run_history)
    return parser.parse_args(arguments)


def main(arguments):
    options = parse_arguments(arguments)
    try:
        for path in options.handler(options):
            print(path)
    except RenderError as error:
        print(f"{PROGRAM}: error: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
