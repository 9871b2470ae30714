#!/usr/bin/env python3
"""The braid of a knot report's snapshot, as docs/FIDELITY.md ("Where the
smooth geometry's K = 301 deficit comes from") measures it:

    knotsweep run --n 3 --out seg.json
    ~/.cache/knotsweep-venv/bin/python tools/braid_geometry.py seg.json [LABEL]

LABEL is a snapshot label (default `before_inversion`). Printed: the largest
turning angles phi between edges, the radius of the circle through each
one's three nodes, and the excess of the discrete elastic rod's curvature
2 tan(phi/2) / l over 2 sin(phi/2) / l (exact on a polygon inscribed in a
circle); the gaps less 2h between non-neighbouring chords and between the
smooth geometry's curves (`solver/src/contact/curve.rs`, sampled at 21
points a piece) over the edges that carry loaded contacts; where on their
pieces the loaded contacts lie; how much longer the curve is than the
polygon there. Needs numpy.
"""
import json
import math
import sys

import numpy as np


def main(path: str, label: str) -> None:
    report = json.load(open(path))
    h = report["params"]["h"]
    snap = next(s for s in report["snapshots"] if s["label"] == label)
    p = np.array(snap["points"])
    n = len(p)
    edge = np.diff(p, axis=0)
    length = np.linalg.norm(edge, axis=1)
    t = edge / length[:, None]
    phi = np.arccos(np.clip((t[:-1] * t[1:]).sum(1), -1.0, 1.0))
    print(f"{path} [{label}] l_k bar {snap['l_k_bar']:.2f}, K {n}, median edge {np.median(length) / h:.3f} h")
    for i in np.argsort(-phi)[:4]:
        excess = 1.0 / math.cos(phi[i] / 2.0) - 1.0
        radius = length[i] / (2.0 * math.sin(phi[i] / 2.0)) / h
        print(
            f"  node {i + 1}: phi {math.degrees(phi[i]):.1f} deg, radius {radius:.2f} h, "
            f"curvature +{100 * excess:.1f} %, bending energy +{100 * ((1 + excess) ** 2 - 1):.1f} %"
        )
    voronoi = 0.5 * (length[:-1] + length[1:])
    der = (np.tan(phi / 2) ** 2 / voronoi).sum() / (np.sin(phi / 2) ** 2 / voronoi).sum()
    print(f"  bending energy of the whole rod, 2 tan(phi/2) over 2 sin(phi/2): {der:.4f}")

    def control(i: int) -> np.ndarray:
        if i < 0:
            return 2 * p[0] - p[-i]
        if i > n - 1:
            return 2 * p[n - 1] - p[2 * (n - 1) - i]
        return p[i]

    def piece(e: int, u: np.ndarray) -> np.ndarray:
        m0 = (control(e - 2) - 8 * control(e - 1) + 8 * control(e + 1) - control(e + 2)) / 12
        m1 = (control(e - 1) - 8 * control(e) + 8 * control(e + 2) - control(e + 3)) / 12
        u = u[:, None]
        u2, u3 = u * u, u**3
        return (2 * u3 - 3 * u2 + 1) * p[e] + (u3 - 2 * u2 + u) * m0 + (-2 * u3 + 3 * u2) * p[e + 1] + (u3 - u2) * m1

    contacts = [np.array(c[k]) for c in snap["contacts"] for k in ("a", "b")]
    near = [int(np.argmin(np.linalg.norm(p[:-1] - x, axis=1))) for x in contacts]
    lo, hi = max(0, min(near) - 5), min(n - 1, max(near) + 6)
    u = np.linspace(0.0, 1.0, 21)
    chords = {e: p[e] + u[:, None] * (p[e + 1] - p[e]) for e in range(lo, hi)}
    curves = {e: piece(e, u) for e in range(lo, hi)}

    def distance(a: np.ndarray, b: np.ndarray) -> float:
        return float(np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1)).min())

    gaps = [
        (distance(chords[a], chords[b]) / h - 2, distance(curves[a], curves[b]) / h - 2)
        for a in range(lo, hi)
        for b in range(a + 3, hi)
        if distance(chords[a], chords[b]) < 2.6 * h
    ]
    chord, curve = (np.sort([g[k] for g in gaps]) for k in (0, 1))
    print(f"  {len(snap['contacts'])} loaded contacts on edges {min(near)}..{max(near)} of {n - 1}")
    print(
        f"  gap - 2h over {len(gaps)} pairs within 2.6 h: chords min {chord[0]:+.3f} h (tenth {chord[9]:+.3f} h), "
        f"curves min {curve[0]:+.3f} h (tenth {curve[9]:+.3f} h)"
    )
    fine = np.linspace(0.0, 1.0, 2001)
    ends = 0
    for x, e0 in zip(contacts, near):
        best = min(
            (float(np.linalg.norm(piece(e, fine) - x, axis=1).min()), e) for e in range(max(0, e0 - 2), min(n - 1, e0 + 2))
        )
        at = int(np.linalg.norm(piece(best[1], fine) - x, axis=1).argmin())
        ends += at in (0, len(fine) - 1)
    print(f"  contact points on a piece's end (smooth geometry's line contacts): {ends} of {len(contacts)}")
    extra = sum(
        np.linalg.norm(np.diff(piece(e, np.linspace(0.0, 1.0, 201)), axis=0), axis=1).sum() - length[e]
        for e in range(lo, hi)
    )
    print(f"  the curve is longer than the polygon over edges {lo}..{hi} by {extra / h:.3f} h")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else "before_inversion")
