#!/usr/bin/python3
"""Plot the SPH dam-break speed/accuracy CSV written by `bench_sph_fluid --csv PATH`.

Usage: /usr/bin/python3 scripts/plot_sph_tradeoff.py PATH.csv [docs/sph_dam_break_tradeoff.png]
Largest relative surge-front error against Martin & Moyce (1952) for t* <= 3 against the simulation time of the
run (steps x time per step), one line per resolution and smoothing length h/dx, markers labelled with the CFL
number.
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/sph_dam_break_tradeoff.png"
    rows = list(csv.DictReader(open(sys.argv[1])))
    if not rows:
        sys.exit("plot_sph_tradeoff: %s has no rows" % sys.argv[1])
    lines = defaultdict(list)
    for r in rows:
        lines[(int(r["particles_across"]), float(r["h_over_dx"]))].append(r)
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for (across, ratio), rs in sorted(lines.items()):
        rs.sort(key=lambda r: float(r["cfl"]))
        x = [int(r["steps"]) * float(r["seconds_per_step"]) for r in rs]
        y = [100.0 * float(r["max_rel_error"]) for r in rs]
        ax.plot(x, y, marker="o", label="%d across L, h = %.1f dx" % (across, ratio))
        for r, xi, yi in zip(rs, x, y):
            ax.annotate("CFL %s" % r["cfl"], (xi, yi), fontsize=7, xytext=(3, 3), textcoords="offset points")
    ax.axhline(10.0, color="grey", linestyle="--", linewidth=1)
    ax.text(0.01, 10.05, "issue target 10%", fontsize=8, color="grey", transform=ax.get_yaxis_transform())
    ax.set_xscale("log")
    ax.set_xlabel("run time to t* = 3 [s] (one thread)")
    ax.set_ylabel("largest surge-front error vs Martin & Moyce [%]")
    ax.set_title("2D dam break: step size and smoothing length against accuracy")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print("wrote", out)


if __name__ == "__main__":
    main()
