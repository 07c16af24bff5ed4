#!/usr/bin/python3
"""Plot the MLS speed/accuracy trade-off CSV written by `bench_mls --csv PATH`.

Usage: /usr/bin/python3 scripts/plot_mls_tradeoff.py PATH.csv [docs/mls_tradeoff.png]
One panel per fit: RMS error against projected points per second, one line per support radius (in units of the
sample spacing h), markers labelled with the iteration cap.
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
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/mls_tradeoff.png"
    rows = list(csv.DictReader(open(sys.argv[1])))
    if not rows:
        sys.exit("plot_mls_tradeoff: %s has no rows" % sys.argv[1])
    fits = list(dict.fromkeys(r["fit"] for r in rows))
    fig, axes = plt.subplots(1, len(fits), figsize=(4.2 * len(fits), 4), sharey=True, squeeze=False)
    for ax, fit in zip(axes[0], fits):
        lines = defaultdict(list)
        for r in rows:
            if r["fit"] == fit:
                lines[float(r["radius_factor"])].append(r)
        for factor, rs in sorted(lines.items()):
            rs.sort(key=lambda r: int(r["max_iterations"]))
            x = [float(r["points_per_s"]) for r in rs]
            y = [float(r["rms_error"]) for r in rs]
            ax.plot(x, y, marker="o", label="r = %.1f h" % factor)
            for r, xi, yi in zip(rs, x, y):
                ax.annotate(r["max_iterations"], (xi, yi), fontsize=7, xytext=(3, 3), textcoords="offset points")
        ax.set_title(fit)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("projected points / s (%s threads)" % rows[0]["threads"])
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].set_ylabel("RMS distance to the true torus")
    axes[0][-1].legend(fontsize=8)
    fig.suptitle("MLS speed/accuracy (labels: iteration cap), %s noisy torus points" % rows[0]["points"])
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print("wrote", out)


if __name__ == "__main__":
    main()
