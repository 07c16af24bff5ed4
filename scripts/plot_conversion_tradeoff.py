#!/usr/bin/python3
"""Plot the texture threshold's speed/accuracy CSV written by `bench_conversion --csv PATH`.

Usage: /usr/bin/python3 scripts/plot_conversion_tradeoff.py PATH.csv [docs/conversion_tradeoff.png]
Left: colour PSNR of the textured mesh against its surfels (mean and worst of four close-up views) over the
colour atlas size; right: the same PSNR over the texture generation time. Markers are labelled with the
texture threshold (the area-weighted mean RGB error (6.1) each patch is refined to).
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/conversion_tradeoff.png"
    rows = sorted(csv.DictReader(open(sys.argv[1])), key=lambda r: float(r["rgb_bytes"]))
    if not rows:
        sys.exit("plot_conversion_tradeoff: %s has no rows" % sys.argv[1])
    fig, (ax_bytes, ax_time) = plt.subplots(1, 2, figsize=(10, 4.2))
    for axis, column, label in ((ax_bytes, "rgb_bytes", "colour atlas [MB, RGB]"),
                                (ax_time, "texture_s", "texture generation [s] (2 threads, median of 3)")):
        scale = 1e-6 if column == "rgb_bytes" else 1.0
        x = [float(r[column]) * scale for r in rows]
        axis.plot(x, [float(r["psnr_mean"]) for r in rows], marker="o", label="mean of 4 views")
        axis.plot(x, [float(r["psnr_worst"]) for r in rows], marker="s", linestyle="--", label="worst view")
        for r, xi in zip(rows, x):
            axis.annotate("%g" % float(r["threshold"]), (xi, float(r["psnr_mean"])), fontsize=7, xytext=(3, 4),
                          textcoords="offset points")
        axis.set_xlabel(label)
        axis.set_ylabel("colour PSNR, mesh vs. surfels [dB]")
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize=8, loc="lower right")
    fig.suptitle("Igea (11,340 triangles): texture threshold (labels) against size, time and fidelity", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print("plot_conversion_tradeoff: wrote", out)


if __name__ == "__main__":
    main()
