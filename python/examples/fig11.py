"""The paper's Fig. 11 from a running sweep service, as in a notebook:
submit the fig11 preset (n = 3, h = 3.4 mm, mu = 0.1 ... 0.7), follow it
with a progress bar, and plot the inversion point l_k bar against the
friction coefficient with the simplified model's snap (Sec. 5) as a line.

    cargo run --release -- serve            # in another terminal
    pip install ./python pandas matplotlib tqdm
    python python/examples/fig11.py --out fig11.png

Points where F bar does not fall through the event (a loop lying down
rather than a snap) are drawn hollow, as on the web page.
"""
import argparse

import matplotlib

matplotlib.use("Agg")  # no display needed; in a notebook leave this out
import matplotlib.pyplot as plt

import knotsweep

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--url", default="http://127.0.0.1:8080")
parser.add_argument("--token", default=None, help="the server's KNOTSWEEP_TOKEN, if it has one")
parser.add_argument("--nodes", type=int, default=None, help="a coarser mesh for a quicker look (e.g. 201)")
parser.add_argument("--sweep", type=int, default=None, help="plot this finished sweep instead of submitting")
parser.add_argument("--out", default="fig11.png")
args = parser.parse_args()

client = knotsweep.Client(args.url, token=args.token)
if args.sweep is None:
    sweep = client.submit(preset="fig11", base={"nodes": args.nodes} if args.nodes else None)
    print(f"sweep {sweep.id}: {sweep.submitted['total']} cases, {sweep.submitted['cached']} cached")
else:
    sweep = client.sweep(args.sweep)
sweep.wait(progress=True)

df = sweep.phase_diagram()  # one row per case: mu, status, l_k_bar, F_bar_before, ..., simplified_l_k_bar
print(df[["mu", "status", "l_k_bar", "F_bar_before", "F_bar_after", "kinetic_energy_ratio"]].to_string(index=False))

fig, ax = plt.subplots(figsize=(5, 4))
inverted = df.dropna(subset=["l_k_bar"])
snap = inverted["F_bar_after"] < inverted["F_bar_before"]
ax.plot(inverted["mu"], inverted["l_k_bar"], "-", color="C0", zorder=1)
ax.scatter(inverted["mu"][snap], inverted["l_k_bar"][snap], color="C0", label="simulation (snap)", zorder=2)
if (~snap).any():
    ax.scatter(inverted["mu"][~snap], inverted["l_k_bar"][~snap], facecolors="white", edgecolors="C0",
               label="simulation (F bar does not fall)", zorder=2)
simplified = df["simplified_l_k_bar"].dropna()
if len(simplified):
    ax.axhline(simplified.iloc[0], color="k", linestyle="--", label="simplified model (no friction)")
ax.set_xlabel(r"friction coefficient $\mu$")
ax.set_ylabel(r"$\bar{l}_k$ at inversion")
ax.set_title(f"Fig. 11: n = 3, h = 3.4 mm (sweep {sweep.id})")
ax.legend()
fig.tight_layout()
fig.savefig(args.out, dpi=150)
print(f"wrote {args.out}")
