#!/usr/bin/python3
"""Plot the MLS speed/accuracy trade-off CSV written by `bench_mls --csv PATH`.

Usage: /usr/bin/python3 scripts/plot_mls_tradeoff.py PATH.csv [docs/mls_tradeoff.png]
One panel per rc fit: RMS error against projected points per second, one line per support radius (in units of the
sample spacing h), markers labelled with the iteration cap; the "pcl order 2" rows (one step, radius r/h) are drawn
in every panel as the reference. A last panel compares one step (cap 1) of every fit over the radii with PCL.
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PCL = "pcl order 2"


def draw_pcl(ax, pcl):
    if not pcl:
        return
    x = [float(r["points_per_s"]) for r in pcl]
    y = [float(r["rms_error"]) for r in pcl]
    ax.plot(x, y, color="black", linestyle="--", marker="s", label="PCL order 2 (r/h)")
    for r, xi, yi in zip(pcl, x, y):
        ax.annotate("%.0f" % float(r["radius_factor"]), (xi, yi), fontsize=7, xytext=(3, -9),
                    textcoords="offset points")


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/mls_tradeoff.png"
    rows = list(csv.DictReader(open(sys.argv[1])))
    if not rows:
        sys.exit("plot_mls_tradeoff: %s has no rows" % sys.argv[1])
    pcl = sorted((r for r in rows if r["fit"] == PCL), key=lambda r: float(r["radius_factor"]))
    fits = [f for f in dict.fromkeys(r["fit"] for r in rows) if f != PCL]
    panels = len(fits) + 1
    cols = min(3, panels)
    nrows = (panels + cols - 1) // cols
    fig, axes = plt.subplots(nrows, cols, figsize=(4.6 * cols, 4.0 * nrows), sharex=True, sharey=True,
                             squeeze=False)
    flat = [ax for row in axes for ax in row]
    for ax, fit in zip(flat, fits):
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
        draw_pcl(ax, pcl)
        ax.set_title("rc " + fit)
    summary = flat[len(fits)]
    for fit in fits:
        rs = sorted((r for r in rows if r["fit"] == fit and int(r["max_iterations"]) == 1),
                    key=lambda r: float(r["radius_factor"]))
        x = [float(r["points_per_s"]) for r in rs]
        y = [float(r["rms_error"]) for r in rs]
        summary.plot(x, y, marker="o", label="rc " + fit)
        for r, xi, yi in zip(rs, x, y):
            summary.annotate("%.0f" % float(r["radius_factor"]), (xi, yi), fontsize=7, xytext=(3, 3),
                             textcoords="offset points")
    draw_pcl(summary, pcl)
    summary.set_title("one step, labels r/h")
    summary.legend(fontsize=7)
    for ax in flat[panels:]:
        ax.set_visible(False)
    for ax in flat[:panels]:
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
        ax.set_xlabel("projected points / s (%s threads)" % rows[0]["threads"])
    for row in axes:
        row[0].set_ylabel("RMS distance to the true torus")
    flat[0].legend(fontsize=7)
    fig.suptitle("MLS speed/accuracy on %s noisy torus points, no normals given (labels: iteration cap; "
                 "G = PCL's weight, W = Wendland)" % rows[0]["points"], fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print("wrote", out)


if __name__ == "__main__":
    main()
