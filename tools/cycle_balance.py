#!/usr/bin/env python3
"""Work against elastic energy over a pull-then-release series (`knotsweep run --loading ... --csv`).

For each stage: the clamps' work over l_k bar in [lo, hi], the integral of F bar d(-l_k bar) (F bar h^2 / EI times
l_k bar = l / h is energy in EI / h, the unit of E bar), against the change of E_stretch_bar + E_bend_bar +
E_twist_bar over the same range, and F bar on the way in and back at given l_k bar (means over +-window).

    python3 tools/cycle_balance.py c.csv --range 260 340 --at 275 325 300
"""
import argparse
import csv


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("--range", nargs=2, type=float, default=[260.0, 340.0], metavar=("LO", "HI"))
    ap.add_argument("--at", nargs="*", type=float, default=[275.0, 325.0])
    ap.add_argument("--window", type=float, default=5.0)
    a = ap.parse_args()
    rows = list(csv.DictReader(open(a.csv)))
    stages = []
    for r in rows:
        if r["stage"] not in stages:
            stages.append(r["stage"])
    lo, hi = a.range
    for s in stages:
        pts = [(float(r["l_k_bar"]), float(r["F_bar"]),
                sum(float(r[k]) for k in ("E_stretch_bar", "E_bend_bar", "E_twist_bar")))
               for r in rows if r["stage"] == s and lo <= float(r["l_k_bar"]) <= hi]
        if len(pts) < 2:
            continue
        work = sum(0.5 * (p[1] + q[1]) * (p[0] - q[0]) for p, q in zip(pts, pts[1:]))
        gain = pts[-1][2] - pts[0][2]
        print(f"stage {s}: l_k bar {pts[0][0]:.1f} -> {pts[-1][0]:.1f}: clamps' work {work:.6f}, "
              f"elastic energy change {gain:.6f}, work / change - 1 = {work / gain - 1:+.1%}")
    for x in a.at:
        f = [[float(r["F_bar"]) for r in rows if r["stage"] == s and abs(float(r["l_k_bar"]) - x) <= a.window]
             for s in stages[:2]]
        if len(f) == 2 and f[0] and f[1]:
            i, b = sum(f[0]) / len(f[0]), sum(f[1]) / len(f[1])
            print(f"F bar at {x:g}: in {i:.6f}, back {b:.6f}, back / in - 1 = {b / i - 1:+.1%}")


if __name__ == "__main__":
    main()
