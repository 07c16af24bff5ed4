#!/usr/bin/python3
"""Plot the paint buffer's speed/accuracy CSV written by `bench_paint_model --csv PATH` (or `--curve --csv PATH`).

Usage: /usr/bin/python3 scripts/plot_paint_tradeoff.py PATH.csv [docs/paint_buffer_tradeoff.png]
Left: RMS error of the wet paint per unit area across a straight stroke (relative to the reference's plateau,
reference at 1/16 of a brush surfel) over the paint transfer time per event; right: the stripe's 10-90 % edge
width over the same time, the reference's as a dashed line. One line per brush, markers labelled with the
pixels per brush surfel.
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
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/paint_buffer_tradeoff.png"
    rows = list(csv.DictReader(open(sys.argv[1])))
    if not rows:
        sys.exit("plot_paint_tradeoff: %s has no rows" % sys.argv[1])
    lines = defaultdict(list)
    for r in rows:
        lines[r["brush"]].append(r)
    fig, (ax, ax_edge) = plt.subplots(1, 2, figsize=(10, 4.4))
    for k, (brush, rs) in enumerate(sorted(lines.items())):
        colour = "C%d" % k
        rs.sort(key=lambda r: float(r["pixels_per_brush_surfel"]))
        x = [float(r["paint_us"]) / 1000.0 for r in rs]
        for axis, column in ((ax, "rms_error"), (ax_edge, "edge_width_mm")):
            y = [max(float(r[column]), 1e-3) for r in rs]
            axis.plot(x, y, marker="o", color=colour, label="%s brush" % brush)
            for r, xi, yi in zip(rs, x, y):
                axis.annotate("%.3g px" % float(r["pixels_per_brush_surfel"]), (xi, yi), fontsize=6, xytext=(3, 3),
                              textcoords="offset points")
        ax_edge.axhline(float(rs[0]["reference_edge_width_mm"]), color=colour, linestyle="--", linewidth=1,
                        label="%s reference (16 px)" % brush)
    for axis, where in ((ax, "lower left"), (ax_edge, "center right")):
        axis.axvline(1000.0 / 120.0, color="grey", linestyle="--", linewidth=1)
        axis.text(1000.0 / 120.0, 0.95, " 120 events/s", fontsize=7, color="grey",
                  transform=axis.get_xaxis_transform())
        axis.set_xscale("log")
        axis.set_yscale("log")
        axis.set_xlabel("paint transfer per event [ms] (1 core, median of 3 runs)")
        axis.legend(fontsize=7, loc=where)
    ax.set_ylabel("RMS error of paint per area across the stroke\n(relative to the reference's plateau)")
    ax_edge.set_ylabel("10-90 % edge width of the stripe [mm]")
    fig.suptitle("Paint buffer pixels per brush surfel: speed against accuracy of a straight stroke", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print("wrote", out)


if __name__ == "__main__":
    main()
