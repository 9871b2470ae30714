#!/usr/bin/env python3
"""The paper's campaign (the 16 distinct cases of the fig7, fig9 and fig11
presets) under both pull protocols: wall time, steps and inversion of each
case, and the adaptive protocol's deviation from the reference.

    cargo build --release
    python3 tools/bench_campaign.py [--jobs 2] [--bin target/release/knotsweep]

Each case runs in its own `knotsweep run` process, `--jobs` at a time; the
times are the reports' wall times (one thread per case). Prints a markdown
table (BENCHMARKS.md, "Pull protocols").
"""
import argparse
import json
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

CASES = (
    [f"--n 3 --h {h}" for h in ("1.6e-3", "2.0e-3", "2.4e-3", "2.8e-3", "3.2e-3")]
    + [f"--n {n}" for n in (1, 2, 4, 5)]
    + [f"--n 3 --h 3.4e-3 --mu {mu}" for mu in ("0.1", "0.2", "0.3", "0.4", "0.5", "0.6", "0.7")]
)
PROTOCOLS = ("reference", "adaptive")


def run(binary, workdir, args, protocol):
    out = Path(workdir) / f"{args.replace(' ', '_')}_{protocol}.json"
    cmd = [binary, "run", *args.split(), "--protocol", protocol, "--out", str(out)]
    subprocess.run(cmd, capture_output=True, check=True)
    report = json.loads(out.read_text())
    stats = report["stats"]
    inversion = (report.get("inversion") or {}).get("l_k_bar")
    return report["status"], inversion, stats["wall_time"], stats["steps"] + stats["relax_steps"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--bin", default="target/release/knotsweep")
    parser.add_argument("--jobs", type=int, default=2)
    opts = parser.parse_args()
    jobs = [(args, p) for args in CASES for p in PROTOCOLS]
    with tempfile.TemporaryDirectory() as workdir, ThreadPoolExecutor(opts.jobs) as pool:
        results = dict(zip(jobs, pool.map(lambda j: run(opts.bin, workdir, *j), jobs)))
    print("| case | reference: l_k bar, wall s, steps | adaptive: l_k bar, wall s, steps | deviation |")
    print("|---|---|---|---|")
    totals = {p: 0.0 for p in PROTOCOLS}
    within = 0
    for args in CASES:
        cells = []
        for p in PROTOCOLS:
            status, inv, wall, steps = results[(args, p)]
            totals[p] += wall
            shown = f"{inv:.2f}" if inv else ("none" if status == "completed" else status)
            cells.append(f"{shown}, {wall:.1f}, {steps}")
        ref, fast = results[(args, "reference")][1], results[(args, "adaptive")][1]
        if ref and fast:
            dev = abs(fast - ref) / ref * 100
            deviation = f"{dev:.2f} %"
            within += dev <= 1.0
        else:
            deviation = "same (none)" if ref == fast else "**one has no inversion**"
            within += ref == fast
        print(f"| `{args}` | {cells[0]} | {cells[1]} | {deviation} |")
    print()
    print(
        f"Total case wall time: reference {totals['reference']:.0f} s, adaptive {totals['adaptive']:.0f} s "
        f"({totals['reference'] / totals['adaptive']:.1f} times less); {within} of {len(CASES)} cases "
        f"within 1 % (or both without an inversion)."
    )


if __name__ == "__main__":
    main()
