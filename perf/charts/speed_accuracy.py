#!/usr/bin/env python3
"""Speed against accuracy charts from perf/accuracy_cost.cpp CSVs.

  speed_accuracy.py CSV [CSV ...] --out PREFIX [--machine-label TEXT ...]

Writes PREFIX_<case>.png per case: log-log error against wall time, one curve per
(backend, model, swept parameter), each point labelled by the swept value (dx, m, PD ratio).
Rows with error nan (failed runs) are left out and listed on stderr. Every written path is
printed. Needs numpy and matplotlib (Debian: python3-numpy python3-matplotlib).
Errors (missing file or column, a bad number) print one line and exit with status 1.
See perf/charts/README.md.
"""
import argparse
import csv
import math
import os
import sys

PROGRAM = "speed_accuracy"

COLUMNS = ["case", "reference", "backend", "model", "spacing_m", "horizon_factor", "pd_ratio", "force_kernel",
           "free_dof", "repeats", "wall_seconds", "error", "status"]

# The parameters a sweep varies, in the order a row is offered to them; force_kernel is not
# one: each kernel gets its own curves (the sweeps run both kernels over the same dx).
FAMILIES = [("spacing_m", "Δx"), ("horizon_factor", "m"), ("pd_ratio", "PD ratio")]


class ChartError(Exception):
    """Bad input: the message names the file, line or column and the reason."""


try:
    import numpy as np
    import matplotlib

    matplotlib.use("Agg")  # files only; no display on the build machines
    import matplotlib.pyplot as plt
except ImportError as missing:
    sys.exit(f"{PROGRAM}: error: {missing}; run with a python3 that has numpy and matplotlib "
             "(Debian's /usr/bin/python3 with python3-matplotlib)")


# ---------------------------------------------------------------------------------------------
# Reading
# ---------------------------------------------------------------------------------------------

def optional_number(text, path, line, column):
    """A float, or None for an empty field (e.g. horizon_factor of a CCM row)."""
    text = text.strip()
    if not text:
        return None
    try:
        return float(text)
    except ValueError:
        raise ChartError(f"{path}:{line}: column '{column}': '{text}' is not a number") from None


def read_rows(path, source):
    """The rows of one CSV as dicts; numbers parsed, `source` names the file in legends."""
    if not os.path.isfile(path):
        raise ChartError(f"{path}: no such file")
    with open(path, newline="") as file:
        reader = csv.DictReader(file)
        if reader.fieldnames is None:
            raise ChartError(f"{path}: empty (no header line)")
        missing = [column for column in COLUMNS if column not in reader.fieldnames]
        if missing:
            raise ChartError(f"{path}: missing column(s) {', '.join(missing)}; "
                             f"the header has {', '.join(reader.fieldnames)}")
        rows = []
        for line, record in enumerate(reader, start=2):
            if None in record or any(record[column] is None for column in COLUMNS):
                raise ChartError(f"{path}:{line}: the row does not have the header's {len(reader.fieldnames)} fields")
            row = {column: record[column].strip() for column in COLUMNS}
            for column in ("spacing_m", "horizon_factor", "pd_ratio", "wall_seconds", "error"):
                row[column] = optional_number(row[column], path, line, column)
            for column in ("spacing_m", "wall_seconds"):
                if row[column] is None:
                    raise ChartError(f"{path}:{line}: column '{column}' is empty")
            if row["error"] is None:
                row["error"] = math.nan
            row["source"] = source
            row["where"] = f"{path}:{line}"
            rows.append(row)
    if not rows:
        raise ChartError(f"{path}: no rows below the header")
    return rows


# ---------------------------------------------------------------------------------------------
# Curves
# ---------------------------------------------------------------------------------------------

def same(a, b):
    """Parameter values equal, None (not applicable) only to None."""
    if a is None or b is None:
        return a is None and b is None
    return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-15)


def value_key(value):
    return None if value is None else round(value, 12)


def format_value(column, value):
    if value is None:
        return "–"
    if column == "spacing_m":
        return f"{value * 1e3:g} mm" if value < 0.01 else f"{value:g} m"
    if column == "pd_ratio":
        return f"{value:.2f}"
    return f"{value:g}"


def split_into_curves(rows):
    """Curves: rows that share backend, model, kernel and all sweep parameters but one, which
    takes at least two values. A row may lie on two curves (the point where a dx sweep and an
    m sweep cross). Rows on no curve come back as single points."""
    curves, on_a_curve = [], set()
    for column, symbol in FAMILIES:
        groups = {}
        for index, row in enumerate(rows):
            fixed = tuple(value_key(row[other]) for other, _ in FAMILIES if other != column)
            key = (row["source"], row["backend"], row["model"], row["force_kernel"], fixed)
            groups.setdefault(key, []).append(index)
        for members in groups.values():
            by_value = {}
            for index in members:
                value = rows[index][column]
                if value is None:
                    continue
                if value_key(value) in by_value:
                    first = rows[by_value[value_key(value)]]
                    print(f"{PROGRAM}: note: {rows[index]['where']} repeats the point of {first['where']}; "
                          "the first is drawn", file=sys.stderr)
                    continue
                by_value[value_key(value)] = index
            if len(by_value) < 2:
                continue
            points = sorted(by_value.values(), key=lambda index: rows[index][column])
            curves.append((column, symbol, points))
            on_a_curve.update(points)
    singles = [index for index in range(len(rows)) if index not in on_a_curve]
    return curves, singles


def curve_label(row, column, symbol, with_source):
    parts = [row["backend"], row["model"]]
    for other, other_symbol in FAMILIES:
        if other == column or row[other] is None:
            continue
        if other == "pd_ratio" and row["model"] != "mixed":
            continue  # 0 for ccm, 1 for pd: says nothing
        if other == "spacing_m":
            parts.append(f"Δx {format_value(other, row[other])}")
        else:
            parts.append(f"{other_symbol} = {format_value(other, row[other])}")
    if row["force_kernel"]:
        parts.append(row["force_kernel"])
    label = ", ".join(parts[1:])
    prefix = f"{row['source']} {row['backend']}" if with_source else row["backend"]
    return f"{prefix}: {label}" + (f"; {symbol} sweep" if column else "")


def point_label(row, column):
    if column == "spacing_m":
        return format_value(column, row[column])
    if column == "horizon_factor":
        return f"m={format_value(column, row[column])}"
    return f"r={format_value(column, row[column])}"


# ---------------------------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------------------------

MARKERS = {"ccm": "o", "pd": "s", "mixed": "^"}
LINESTYLES = {"spacing_m": "-", "horizon_factor": "--", "pd_ratio": ":"}
# Where each family's point labels go, so that a point on two curves keeps both readable.
LABEL_OFFSETS = {"spacing_m": (4, 3), "horizon_factor": (4, -10), "pd_ratio": (-30, 5)}


def draw_case(case, rows, out_path, title_label, with_source, dpi):
    figure, axes = plt.subplots(figsize=(8.0, 5.5), constrained_layout=True)
    curves, singles = split_into_curves(rows)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    colour_of = {}

    def colour(row):
        key = (row["source"], row["backend"], row["model"], row["force_kernel"])
        if key not in colour_of:
            colour_of[key] = colours[len(colour_of) % len(colours)]
        return colour_of[key]

    for column, symbol, points in curves:
        first = rows[points[0]]
        x = np.array([rows[index]["wall_seconds"] for index in points])
        y = np.array([rows[index]["error"] for index in points])
        axes.plot(x, y, marker=MARKERS.get(first["model"], "o"), linestyle=LINESTYLES[column], color=colour(first),
                  label=curve_label(first, column, symbol, with_source))
        for index in points:
            axes.annotate(point_label(rows[index], column), (rows[index]["wall_seconds"], rows[index]["error"]),
                          textcoords="offset points", xytext=LABEL_OFFSETS[column], fontsize=7, color=colour(first))
    for index in singles:
        row = rows[index]
        axes.plot([row["wall_seconds"]], [row["error"]], marker=MARKERS.get(row["model"], "o"), linestyle="none",
                  color=colour(row), label=curve_label(row, None, None, with_source))
    axes.set_xscale("log")
    axes.set_yscale("log")
    axes.set_xlabel("wall time, model build to answer [s]")
    axes.set_ylabel("error against the reference (relative)")
    title = f"{case}: error against {rows[0]['reference']}"
    if title_label:
        title += f"\n{title_label}"
    axes.set_title(title, fontsize=10)
    axes.grid(True, which="both", linewidth=0.3)
    axes.legend(fontsize=7, loc="best")
    if os.path.dirname(out_path):
        os.makedirs(os.path.dirname(out_path), exist_ok=True)
    figure.savefig(out_path, dpi=dpi, bbox_inches="tight")
    plt.close(figure)


def run(options):
    labels = options.machine_label or []
    if len(labels) > 1 and len(labels) != len(options.csv):
        raise ChartError(f"--machine-label: {len(labels)} labels for {len(options.csv)} CSV files "
                         "(give one for the title, or one per CSV)")
    per_file = len(labels) == len(options.csv) and len(options.csv) > 1
    rows = []
    for number, path in enumerate(options.csv):
        source = labels[number] if per_file else os.path.splitext(os.path.basename(path))[0]
        rows += read_rows(path, source)
    with_source = len(options.csv) > 1
    title_label = labels[0] if len(labels) == 1 else ""

    cases = []
    for row in rows:
        if row["case"] not in cases:
            cases.append(row["case"])
    written = []
    for case in cases:
        drawn = []
        for row in (row for row in rows if row["case"] == case):
            if math.isnan(row["error"]) or row["error"] <= 0.0 or not row["wall_seconds"] > 0.0:
                what = "error nan" if math.isnan(row["error"]) else \
                    f"error {row['error']:g}" if row["error"] <= 0.0 else f"wall time {row['wall_seconds']:g} s"
                print(f"{PROGRAM}: skipped {row['where']} ({case} {row['backend']} {row['model']} "
                      f"dx {format_value('spacing_m', row['spacing_m'])}"
                      f"{'' if row['horizon_factor'] is None else ', m = ' + format_value('horizon_factor', row['horizon_factor'])}"
                      f"{', ' + row['force_kernel'] if row['force_kernel'] else ''}): {what}"
                      f"{', ' + row['status'] if row['status'] and row['status'] != 'ok' else ''}",
                      file=sys.stderr)
                continue
            drawn.append(row)
        if not drawn:
            print(f"{PROGRAM}: {case}: no row with a finite error; no figure", file=sys.stderr)
            continue
        out_path = f"{options.out}_{case}.png"
        draw_case(case, drawn, out_path, title_label, with_source, options.dpi)
        written.append(out_path)
    if not written:
        raise ChartError("no row of any case has a finite error; nothing drawn")
    return written


# ---------------------------------------------------------------------------------------------
# Command line
# ---------------------------------------------------------------------------------------------

class ArgumentParser(argparse.ArgumentParser):
    def error(self, message):
        self.print_usage(sys.stderr)
        self.exit(1, f"{PROGRAM}: error: {message}\n")


def positive_whole(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a whole number") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"'{text}' is not positive")
    return value


def parse_arguments(arguments):
    parser = ArgumentParser(prog=PROGRAM, description=__doc__.split("\n\n")[0],
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("csv", nargs="+", help="CSV files of perishell_perf_accuracy_cost")
    parser.add_argument("--out", required=True, metavar="PREFIX", help="writes PREFIX_<case>.png")
    parser.add_argument("--machine-label", action="append", metavar="TEXT",
                        help="once: a line under every title (e.g. the machine); once per CSV: names "
                             "each file's curves in the legend")
    parser.add_argument("--dpi", type=positive_whole, default=150, help="resolution (default: 150)")
    return parser.parse_args(arguments)


def main(arguments):
    options = parse_arguments(arguments)
    try:
        for path in run(options):
            print(path)
    except ChartError as error:
        print(f"{PROGRAM}: error: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
