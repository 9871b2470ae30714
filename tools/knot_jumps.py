#!/usr/bin/env python3
"""The knot's jumps in a pull: the figures of docs/FIDELITY.md ("The knot's
jump") behind `InversionCriteria::knot_jump`.

    knotsweep run --n 2 --length 1 --h 2e-4 --mu 0.05 --youngs-modulus 1.8e6 \
        --density 1000 --poisson-ratio 0.5 --out r.json
    python3 tools/knot_jumps.py r.json [more reports]

For every report, the samples whose knot's own length fell the most against
the clamps' travel (l_k bar's fall) since the sample before, in the same
stage: that ratio, l_k bar and the own length before and after, H bar over
its largest within the 10 l_k bar before, F bar before and after. A sample
right after a restart is marked: its fall spans the settling too.
"""
import json
import sys
from pathlib import Path

SHOWN = 6
WINDOW = 10.0


def main(paths: list[str]) -> None:
    for path in paths:
        report = json.loads(Path(path).read_text())
        series = report["series"]
        restarts = {p["from_l_k_bar"] for p in report.get("phases", []) if p["phase"] in ("snap", "fallback")}
        rows = []
        for j in range(1, len(series)):
            a, b = series[j - 1], series[j]
            travel = a["l_k_bar"] - b["l_k_bar"]
            if a["stage"] != b["stage"] or travel <= 0:
                continue
            largest = max(
                (s["H_bar"] for s in series[:j] if s["l_k_bar"] - b["l_k_bar"] <= WINDOW and s["stage"] == b["stage"]),
                default=0.0,
            )
            fall = (a["l_k_arc_bar"] - b["l_k_arc_bar"]) / travel
            after_restart = any(abs(a["l_k_bar"] - r) < 1e-9 for r in restarts)
            rows.append((fall, a, b, b["H_bar"] / largest if largest > 0 else 0.0, after_restart))
        rows.sort(key=lambda r: -r[0])
        print(f"{path}: the {SHOWN} largest falls of the own length over the clamps' travel")
        print("| fall / travel | l_k bar | own length | H bar / largest | F bar | after a restart |")
        print("|---|---|---|---|---|---|")
        for fall, a, b, h, restart in rows[:SHOWN]:
            print(
                f"| {fall:.2f} | {a['l_k_bar']:.2f} | {a['l_k_arc_bar']:.2f} -> {b['l_k_arc_bar']:.2f} | {h:.4f} | "
                f"{a['F_bar']:.4f} -> {b['F_bar']:.4f} | {'yes' if restart else ''} |"
            )


if __name__ == "__main__":
    main(sys.argv[1:])
