#!/usr/bin/env python3
"""F bar of knotsweep runs against the paper's code's (docs/FIDELITY.md).

usage: tools/papercode_compare.py REFERENCE.csv RUN [RUN ...] [--at 260,220,170]

REFERENCE.csv: a run of the paper's public code (columns t, l_c_over_L, l_k_bar,
F_bar, contacts; the project's copies are in ../shared/reference/). RUN: the
series of `knotsweep run ... --csv RUN.csv`, or a case report (`knotsweep run
--out RUN.json`, or a file of `knotsweep reproduce --raw DIR`). Both curves are averaged over
l_k bar +-1 around each point (the paper's code's force swings with the
stick-slip of its contacts); prints ours / the paper's code's and the deviation.
"""
import argparse
import csv
import json


def window_mean(series, x, half=1.0):
    values = [f for l, f in series if abs(l - x) <= half]
    return sum(values) / len(values) if values else None


def series(path):
    """(l_k bar, F bar) of a run's CSV series or JSON report."""
    if path.endswith(".json"):
        return [(s["l_k_bar"], s["F_bar"]) for s in json.load(open(path))["series"]]
    return [(float(r["l_k_bar"]), float(r["F_bar"])) for r in csv.DictReader(open(path))]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("reference")
    parser.add_argument("runs", nargs="+")
    parser.add_argument("--at", default="300,260,220,200,180,170,160")
    args = parser.parse_args()
    rows = list(csv.reader(line for line in open(args.reference) if not line.startswith("#")))
    header = rows[0]
    l_col, f_col = header.index("l_k_bar"), header.index("F_bar")
    paper = [(float(r[l_col]), float(r[f_col])) for r in rows[1:]]
    points = [float(x) for x in args.at.split(",")]
    for run in args.runs:
        ours = series(run)
        cells = []
        for x in points:
            a, b = window_mean(ours, x), window_mean(paper, x)
            if a is None or b is None:
                cells.append(f"{x:g}: -")
            else:
                cells.append(f"{x:g}: {a:.4f}/{b:.4f} ({100 * (a - b) / b:+.1f} %)")
        print(f"{run}: " + "; ".join(cells))


if __name__ == "__main__":
    main()
