#!/usr/bin/python3
"""Plot the paint buffer's speed/accuracy CSV written by `bench_paint_model --csv PATH`.

Usage: /usr/bin/python3 scripts/plot_paint_tradeoff.py PATH.csv [docs/paint_buffer_tradeoff.png]
Colour error across a painted stripe (RMS over the probes, against a reference at 1/16 of a brush surfel) over
the paint transfer time per event, one line per brush, markers labelled with the pixels per brush surfel.
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
    fig, ax = plt.subplots(figsize=(7, 4.4))
    for brush, rs in sorted(lines.items()):
        rs.sort(key=lambda r: float(r["pixels_per_brush_surfel"]))
        x = [float(r["paint_us"]) / 1000.0 for r in rs]
        y = [max(float(r["rms_error"]), 1e-4) for r in rs]
        ax.plot(x, y, marker="o", label="%s brush" % brush)
        for r, xi, yi in zip(rs, x, y):
            ax.annotate("%s px" % r["pixels_per_brush_surfel"], (xi, yi), fontsize=6, xytext=(3, 3),
                        textcoords="offset points")
    ax.axvline(1000.0 / 120.0, color="grey", linestyle="--", linewidth=1)
    ax.text(1000.0 / 120.0, 0.95, " 120 events/s", fontsize=7, color="grey", transform=ax.get_xaxis_transform())
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("paint transfer per event [ms] (buffer, exchange, resampling; 1 core, median)")
    ax.set_ylabel("RMS colour error across the stripe (0..1)")
    ax.set_title("Paint buffer pixels per brush surfel: speed against colour accuracy", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print("wrote", out)


if __name__ == "__main__":
    main()
