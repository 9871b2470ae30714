#!/usr/bin/env python3
"""F bar of two `knotsweep run --csv` series side by side: the second's mean over +-1 in l_k bar
against the first's, at the given l_k bar values.

    tools/compare_series.py reference.csv adaptive.csv 300 250 220 200 180 170 160
"""
import csv
import sys


def load(path):
    return [(float(r["l_k_bar"]), float(r["F_bar"])) for r in csv.DictReader(open(path))]


def near(series, x, w=1.0):
    values = [f for l, f in series if abs(l - x) <= w]
    return sum(values) / len(values) if values else None


def main():
    first, second = load(sys.argv[1]), load(sys.argv[2])
    print("l_k_bar,F_bar_first,F_bar_second,change_percent")
    for x in map(float, sys.argv[3:]):
        a, b = near(first, x), near(second, x)
        change = "" if a is None or b is None else f"{(b - a) / a * 100:+.1f}"
        print(f"{x:g},{a},{b},{change}")


if __name__ == "__main__":
    main()
