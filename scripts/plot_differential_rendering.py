#!/usr/bin/python3
"""Plot the differential rendering scatter written by `bench_paint_rendering --csv PATH` (thesis 5.8, Table 5.1).

Usage: /usr/bin/python3 scripts/plot_differential_rendering.py PATH.csv [docs/differential_rendering.png]
Time of each differential update against the surfels it updated (removed + added): every event of a painted
stroke and recoloured patches of growing size on the 750k sphere at 1280x720, the full update of the same
state as a line, the thesis' 5,000 surfels in 15 ms and the 2 ms target as markers.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/differential_rendering.png"
    rows = list(csv.DictReader(open(sys.argv[1])))
    if not rows:
        sys.exit("plot_differential_rendering: %s has no rows" % sys.argv[1])
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for kind, colour, label in (("stroke", "C0", "painted stroke, one event each"),
                                ("patch", "C1", "recoloured patches")):
        pts = [(int(r["updated_surfels"]), float(r["ms"])) for r in rows if r["kind"] == kind]
        if pts:
            ax.scatter([p[0] for p in pts], [p[1] for p in pts], s=10, color=colour, label=label, alpha=0.7)
    full = [float(r["ms"]) for r in rows if r["kind"] == "full"]
    if full:
        ax.axhline(full[0], color="k", linestyle="--", linewidth=1, label="full update (%.0f ms)" % full[0])
    ax.scatter([5000], [15], marker="x", color="C3", s=60, label="thesis: 5,000 surfels in 15 ms")
    ax.axhline(2, color="C2", linestyle=":", linewidth=1, label="target: 2 ms at 5,000")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("surfels updated (removed + added)")
    ax.set_ylabel("differential update [ms]")
    ax.set_title("Differential rendering, 750k surfels, 1280x720, 2 threads", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print("wrote", out)


if __name__ == "__main__":
    main()
