#!/usr/bin/env python3
"""F bar of two series side by side: the second's mean over +-W in l_k bar (W = 1 unless `--window W`)
against the first's, at the given l_k bar values. A series is a `knotsweep run --csv` file or a file with
the same `l_k_bar` and `F_bar` columns (lines starting with # are skipped, as in ../shared/reference).

    tools/compare_series.py reference.csv adaptive.csv 300 250 220 200 180 170 160
    tools/compare_series.py --window 10 reference.csv adaptive.csv 300 220 170
"""
import argparse
import csv


def load(path):
    with open(path) as f:
        rows = csv.DictReader(line for line in f if not line.startswith("#"))
        return [(float(r["l_k_bar"]), float(r["F_bar"])) for r in rows]


def near(series, x, w):
    values = [f for l, f in series if abs(l - x) <= w]
    return sum(values) / len(values) if values else None


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--window", type=float, default=1.0, help="half-width of the mean in l_k bar")
    parser.add_argument("first")
    parser.add_argument("second")
    parser.add_argument("at", type=float, nargs="+")
    args = parser.parse_args()
    first, second = load(args.first), load(args.second)
    print("l_k_bar,F_bar_first,F_bar_second,change_percent")
    for x in args.at:
        a, b = near(first, x, args.window), near(second, x, args.window)
        change = "" if a is None or b is None else f"{(b - a) / a * 100:+.1f}"
        print(f"{x:g},{a},{b},{change}")


if __name__ == "__main__":
    main()
