#!/usr/bin/env python3
"""Render results of `perishell run` to PNG.

  damage   nodal field snapshots from the XDMF time series (io/xdmf_writer.hpp): a flat
           model as a 2-D projection, a curved shell (cylinder, prism) in 3-D
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
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
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

# --view auto draws in 3-D when the model's smallest bounding-box extent is more than this
# fraction of its largest: a cylinder or prism is; a plate (extent 0 across) is not.
FLAT_FRACTION = 0.01
DEFAULT_ELEVATION = 20.0   # degrees above the x-y plane
DEFAULT_AZIMUTH = -60.0    # degrees about z from +x (matplotlib's default azimuth)
PANEL_INCHES = 4.5         # side of each (square) mplot3d axes
LIGHT_AMBIENT = 0.6        # a face edge-on to the light keeps 60 % of its colour-map colour
LIGHT_HIGHLIGHT = 0.3      # grey added where a face mirrors the light (a black shell still reads 3-D)


def resolve_view(coordinates, view):
    """'3d' for --view 3d, and for --view auto on a model that is not flat; else the view
    unchanged ('auto' then drops the coordinate of smallest extent, per snapshot)."""
    if view != "auto":
        return view
    extents = np.ptp(coordinates, axis=0)
    largest = extents.max()
    return "3d" if largest > 0 and extents.min() > FLAT_FRACTION * largest else "auto"


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


class Snapshot3D:
    def __init__(self, time, coordinates, quads, values):
        self.time = time
        self.coordinates = coordinates  # nodes x 3, deformed when --deformed
        self.quads = quads              # elements x 4
        self.values = values            # nodes


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
    if view == "3d":
        return Snapshot3D(step.time, coordinates, quads, values)
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


def camera_vectors(elevation, azimuth):
    """Unit vectors of the view: towards the viewer, screen right, screen up (mplot3d's camera)."""
    e, a = math.radians(elevation), math.radians(azimuth)
    towards_viewer = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    right = np.array([-math.sin(a), math.cos(a), 0.0])
    up = np.cross(towards_viewer, right)
    return towards_viewer, right, up


def box_3d(snapshots):
    """Shared axis limits of all panels (lows, highs); an extent under 2 % of the largest
    (a plate drawn with --view 3d) is widened to 2 % about its middle."""
    lows = np.min([s.coordinates.min(axis=0) for s in snapshots], axis=0)
    highs = np.max([s.coordinates.max(axis=0) for s in snapshots], axis=0)
    largest = max(float((highs - lows).max()), 1e-12)
    middle = 0.5 * (lows + highs)
    half = np.maximum(0.5 * (highs - lows), 0.01 * largest)
    return middle - half, middle + half


def set_up_axes_3d(axes, box, angles):
    """Limits, equal aspect (the box's sides in proportion to the data's extents), camera, labels."""
    lows, highs = box
    axes.set_xlim(lows[0], highs[0])
    axes.set_ylim(lows[1], highs[1])
    axes.set_zlim(lows[2], highs[2])
    axes.set_box_aspect(highs - lows)
    axes.view_init(elev=angles[0], azim=angles[1])
    extents = highs - lows
    for axis, name, extent in zip((axes.xaxis, axes.yaxis, axes.zaxis), "xyz", extents):
        # Fewer ticks on the shorter sides, so that their labels do not run together.
        # No ticks across a plate drawn in 3-D (its box side is widened to 2 %, box_3d).
        bins = int(min(max(round(5.0 * extent / extents.max()), 1), 4))
        axis.set_major_locator(matplotlib.ticker.MaxNLocator(nbins=bins) if extent > 0.05 * extents.max()
                               else matplotlib.ticker.NullLocator())
        axis.set_label_text(f"{name} [m]", fontsize=7)
        axis.labelpad = 2
    axes.tick_params(labelsize=6, pad=-2)
    axes.patch.set_alpha(0.0)  # panels may overlap in their empty corners (layout_3d)


def draw_snapshot_3d(axes, snapshot, shading, norm, cmap, angles, light):
    """Quads (flat) or their two triangles (gouraud: each the mean of its 3 nodes) as one
    Poly3DCollection, depth-sorted by mplot3d. Edges are drawn in the face colour, 0.4 pt wide:
    that covers the antialiasing seams between faces (thinner, the background shows through as
    a light lattice; black, a 19k-quad mesh comes out black). With light (two-sided, |n . l|,
    from near the camera), each face keeps LIGHT_AMBIENT of its colour-map colour edge-on and
    all of it facing the light, plus a faint grey highlight, so that a shell of one colour
    (undamaged: black in inferno) still shows its shape."""
    quads = snapshot.quads
    if shading == "flat":
        faces = quads
    else:
        faces = np.stack([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]], axis=1).reshape(-1, 3)
    vertices = snapshot.coordinates[faces]
    colours = cmap(norm(snapshot.values[faces].mean(axis=1)))
    if light:
        if faces.shape[1] == 4:
            normals = np.cross(vertices[:, 2] - vertices[:, 0], vertices[:, 3] - vertices[:, 1])
        else:
            normals = np.cross(vertices[:, 1] - vertices[:, 0], vertices[:, 2] - vertices[:, 0])
        lengths = np.linalg.norm(normals, axis=1)
        towards_viewer, right, up = camera_vectors(*angles)
        light_direction = towards_viewer + 0.3 * up - 0.2 * right
        light_direction /= np.linalg.norm(light_direction)
        half_vector = light_direction + towards_viewer
        half_vector /= np.linalg.norm(half_vector)
        safe = np.where(lengths > 0, lengths, 1.0)
        diffuse = np.where(lengths > 0, np.abs(normals @ light_direction) / safe, 1.0)  # degenerate: lit
        highlight = np.where(lengths > 0, np.abs(normals @ half_vector) / safe, 0.0) ** 6
        colours[:, :3] = np.minimum(colours[:, :3] * (LIGHT_AMBIENT + (1.0 - LIGHT_AMBIENT) * diffuse)[:, None]
                                    + LIGHT_HIGHLIGHT * highlight[:, None], 1.0)
    axes.add_collection3d(Poly3DCollection(vertices, facecolors=colours, edgecolors=colours, linewidths=0.4))


def content_bbox_3d(axes, box, renderer):
    """Display-coordinate extent of what a 3-D panel draws: the projected box and the axes'
    tick labels and axis labels (not its square frame, which is mostly empty for a long shell)."""
    from matplotlib.transforms import Bbox
    from mpl_toolkits.mplot3d import proj3d

    lows, highs = box
    corners = np.array([[x, y, z] for x in (lows[0], highs[0]) for y in (lows[1], highs[1])
                        for z in (lows[2], highs[2])])
    xs, ys, _ = proj3d.proj_transform(corners[:, 0], corners[:, 1], corners[:, 2], axes.M)
    points = axes.transData.transform(np.column_stack([xs, ys]))
    extents = [Bbox.from_extents(*points.min(axis=0), *points.max(axis=0))]
    extents += [axis.get_tightbbox(renderer) for axis in (axes.xaxis, axes.yaxis, axes.zaxis)]
    return Bbox.union([extent for extent in extents if extent is not None and np.isfinite(extent.bounds).all()])


def layout_3d(figure, panels, box):
    """Place square 3-D axes side by side so that their drawn contents (content_bbox_3d), not
    their squares, follow one another 0.15 in apart. Returns each axes' left [in], the right
    end of the last contents [in], and per panel the contents' left margin in its square, width,
    top and bottom [in]."""
    dpi = figure.dpi
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    offsets = []
    for axes in panels:
        content = content_bbox_3d(axes, box, renderer)
        frame = axes.get_window_extent(renderer)
        offsets.append(((content.x0 - frame.x0) / dpi, content.width / dpi, (content.y1 - frame.y0) / dpi,
                        (content.y0 - frame.y0) / dpi))
    cursor = 0.0
    positions = []
    for left_margin, width, _, _ in offsets:
        positions.append(cursor - left_margin)
        cursor += width + 0.15
    return positions, cursor, offsets


def draw_figure_3d(snapshots, titles, suptitle, options, norm, cmap, box, angles, path):
    """One PNG: a 3-D panel per snapshot, a shared colour bar, cropped to what is drawn."""
    from matplotlib.transforms import Bbox

    count = len(snapshots)
    side = PANEL_INCHES
    figure = plt.figure(figsize=(side * count + 1.5, side))
    panels = [figure.add_axes([index * side / (side * count + 1.5), 0.0, side / (side * count + 1.5), 1.0],
                              projection="3d") for index in range(count)]
    for axes in panels:
        set_up_axes_3d(axes, box, angles)
    # Pass 1 (empty axes, cheap): where each panel's contents lie inside its square.
    positions, right_end, offsets = layout_3d(figure, panels, box)
    width = right_end + 1.3  # + colour bar and its labels
    figure.set_size_inches(width, side)
    for axes, left, (_, _, top, _), title in zip(panels, positions, offsets, titles):
        axes.set_position([left / width, 0.0, side / width, 1.0])
        # Just above the contents; y given, so not moved above the (mostly empty) square, and
        # set again, as Axes3D.set_title scales it by 0.92.
        axes.set_title(title, fontsize=10, y=top / side + 0.02)
        axes.title.set_y(top / side + 0.02)
    # The colour bar spans the middle 80 % of the drawn height, at least 1.6 in.
    bottom = min(offset[3] for offset in offsets)
    top = max(offset[2] for offset in offsets)
    bar = max(0.8 * (top - bottom), min(1.6, 0.9 * side))
    bar_bottom = min(max(0.5 * (top + bottom - bar), 0.0), side - bar)
    colour_axes = figure.add_axes([(right_end + 0.1) / width, bar_bottom / side, 0.15 / width, bar / side])
    figure.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), cax=colour_axes, label=options.field)
    overall_title = figure.suptitle(suptitle, y=top / side + 0.09, va="bottom") if suptitle else None
    # Pass 2 (still empty): the crop box, in inches.
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    extents = [content_bbox_3d(axes, box, renderer) for axes in panels]
    extents += [axes.title.get_window_extent(renderer) for axes in panels]
    extents.append(colour_axes.get_tightbbox(renderer))
    if overall_title is not None:
        extents.append(overall_title.get_window_extent(renderer))
    crop = Bbox.union(extents).transformed(figure.dpi_scale_trans.inverted()).padded(0.08)
    light = not options.no_light
    for axes, snapshot in zip(panels, snapshots):
        draw_snapshot_3d(axes, snapshot, options.shading, norm, cmap, angles, light)
    figure.savefig(path, dpi=options.dpi, bbox_inches=crop)
    plt.close(figure)


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
    try:
        cmap = matplotlib.colormaps[options.cmap]
    except KeyError:
        raise RenderError(f"--cmap: '{options.cmap}' is not a matplotlib colour map "
                          "(e.g. inferno, viridis, plasma, cividis, coolwarm)") from None
    steps = read_xdmf_steps(options.xdmf)
    picked = pick_steps(steps, options.times)
    mesh_step = picked[0]
    coordinates = read_dataset(mesh_step.geometry).reshape(-1, 3).astype(float)
    quads = read_dataset(mesh_step.topology).reshape(-1, 4).astype(np.int64)
    if quads.size and (quads.min() < 0 or quads.max() >= coordinates.shape[0]):
        raise RenderError(f"{mesh_step.topology[0]}: topology refers to nodes outside 0..{coordinates.shape[0] - 1}")
    view = resolve_view(coordinates, options.view)
    angles_given = options.elev is not None or options.azim is not None
    if view in ("xy", "xz", "yz") and angles_given:
        raise RenderError(f"--elev/--azim set the 3-D camera, but --view {view} draws a 2-D projection "
                          "(give --view 3d or auto)")
    snapshots = [load_snapshot(step, options.field, (coordinates, quads), options.deformed, view)
                 for step in picked]
    vmin, vmax = colour_range(options.field, snapshots, options.vmin, options.vmax)
    label = options.field + (f" (deformed × {options.deformed:g})" if options.deformed is not None else "")
    prefix = options.out or os.path.splitext(options.xdmf)[0]
    if os.path.dirname(prefix):
        os.makedirs(os.path.dirname(prefix), exist_ok=True)
    if view == "3d":
        return draw_figures_3d(options, snapshots, (vmin, vmax), cmap, label, prefix)
    written = []

    for snapshot in snapshots:
        figure, axes = plt.subplots(figsize=figure_size(snapshot, 1), constrained_layout=True)
        artist = draw_snapshot(axes, snapshot, options.shading, vmin, vmax, cmap)
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
            artist = draw_snapshot(axes, snapshot, options.shading, vmin, vmax, cmap)
        figure.suptitle(label)
        figure.colorbar(artist, ax=list(panels[0]), label=options.field, shrink=0.9)
        path = f"{prefix}_{options.field}_panel.png"
        figure.savefig(path, dpi=options.dpi, bbox_inches="tight")
        plt.close(figure)
        written.append(path)
    return written


def draw_figures_3d(options, snapshots, colour_limits, cmap, label, prefix):
    """The same files as the 2-D path: one PNG per snapshot and, for several, the panel."""
    angles = (DEFAULT_ELEVATION if options.elev is None else options.elev,
              DEFAULT_AZIMUTH if options.azim is None else options.azim)
    norm = matplotlib.colors.Normalize(*colour_limits)
    box = box_3d(snapshots)  # one box for all: deformations compare across panels
    written = []
    for snapshot in snapshots:
        path = f"{prefix}_{options.field}_{round(snapshot.time * 1e9)}ns.png"
        draw_figure_3d([snapshot], [f"{label} at t = {snapshot.time * 1e6:.3f} µs"], None,
                       options, norm, cmap, box, angles, path)
        written.append(path)
    if len(snapshots) > 1:
        path = f"{prefix}_{options.field}_panel.png"
        draw_figure_3d(snapshots, [f"t = {snapshot.time * 1e6:.3f} µs" for snapshot in snapshots], label,
                       options, norm, cmap, box, angles, path)
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


def angle_in(low, high):
    def angle(text):
        value = finite_number(text)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{value:g} degrees is outside [{low:g}, {high:g}]")
        return value
    return angle


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
    damage.add_argument("--view", choices=["xy", "xz", "yz", "3d", "auto"], default="auto",
                        help="projection plane, or 3d (auto: 3d when the smallest bounding-box extent "
                             f"is over {FLAT_FRACTION * 100:g} %% of the largest, else drop the coordinate of "
                             "smallest extent)")
    damage.add_argument("--elev", type=angle_in(-90.0, 90.0), metavar="DEGREES",
                        help=f"3-D camera elevation above the x-y plane (default: {DEFAULT_ELEVATION:g})")
    damage.add_argument("--azim", type=angle_in(-360.0, 360.0), metavar="DEGREES",
                        help=f"3-D camera azimuth about z from +x (default: {DEFAULT_AZIMUTH:g})")
    damage.add_argument("--no-light", action="store_true",
                        help="3-D: exact colour-map colours (no dimming of faces turned from the light, "
                             "no highlight)")
    damage.add_argument("--shading", choices=["gouraud", "flat"], default="gouraud",
                        help="gouraud: nodal values interpolated (3-D: two triangles per quad, each "
                             "its nodes' mean); flat: one colour per quad, the mean")
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
