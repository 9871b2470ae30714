#!/usr/bin/env python3
"""How each detected inversion looks: the figures of docs/FIDELITY.md ("Left
open") that tell a force-releasing snap from a loop lying down.

    cargo run --release -- reproduce --raw raw
    python3 tools/inversion_events.py raw

For every case report in the directory: the inversion's l_k bar, F bar after
over F bar before, and the kinetic energy over its median. For Fig. 11's
cases above mu = 0.4 also: the kinetic energy's largest over its median
between l_k bar 160 and 100 (its scatter without an event), where H bar
first falls below FLAT after the detection, and H bar's range from there.
"""
import json
import statistics
import sys
from pathlib import Path

FLAT = 0.005


def main(raw: Path) -> None:
    print("| case | l_k bar | F after / before | kinetic energy / median |")
    print("|---|---|---|---|")
    lying = []
    for path in sorted(raw.glob("*.json")):
        report = json.loads(path.read_text())
        inv = report.get("inversion")
        if not inv:
            print(f"| {path.stem} | none | | |")
            continue
        ratio = inv["F_bar_after"] / inv["F_bar_before"]
        print(f"| {path.stem} | {inv['l_k_bar']:.2f} | {ratio:.3f} | {inv['kinetic_energy_ratio']:.1f} |")
        if path.stem.startswith("fig11_mu") and report["params"]["mu"] > 0.4:
            lying.append((path.stem, report))
    if not lying:
        return
    print()
    print("| case | kinetic energy peak / median, l_k bar 160-100 | flat (H bar < 0.005) at l_k bar | H bar from there |")
    print("|---|---|---|---|")
    for name, report in lying:
        series, inv = report["series"], report["inversion"]
        ke = [s["kinetic_energy"] for s in series if 100 < s["l_k_bar"] < 160]
        after = series[inv["sample"]:]
        flat = next((k for k, s in enumerate(after) if s["H_bar"] < FLAT), None)
        if flat is None:
            print(f"| {name} | {max(ke) / statistics.median(ke):.1f} | never | |")
            continue
        h = [s["H_bar"] for s in after[flat:]]
        print(f"| {name} | {max(ke) / statistics.median(ke):.1f} | {after[flat]['l_k_bar']:.2f} | {min(h):.4f}-{max(h):.4f} |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(Path(sys.argv[1]))
