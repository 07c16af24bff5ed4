#!/usr/bin/python3
"""Plot the thin-shell speed/accuracy CSV written by `bench_shell_accuracy --csv PATH`.

Usage: /usr/bin/python3 scripts/plot_shell_tradeoff.py PATH.csv [docs/shell_tradeoff.png]
Relative bending-energy error against the analytic value (left: sheet bent onto a cylinder, right: inflated
sphere) over the time per force evaluation, one line per neighbour count k (about k/2 fibers per node), markers
labelled with the node count.
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
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/shell_tradeoff.png"
    rows = list(csv.DictReader(open(sys.argv[1])))
    if not rows:
        sys.exit("plot_shell_tradeoff: %s has no rows" % sys.argv[1])
    shapes = ["cylinder", "sphere"]
    titles = {"cylinder": "sheet bent onto a cylinder (r = 0.6)", "sphere": "unit sphere inflated by 1.25"}
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
    for ax, shape in zip(axes, shapes):
        lines = defaultdict(list)
        for r in rows:
            if r["shape"] == shape:
                lines[int(r["neighbor_count"])].append(r)
        for k, rs in sorted(lines.items()):
            rs.sort(key=lambda r: int(r["nodes"]))
            x = [float(r["ms_per_eval_fastest"]) for r in rs]
            y = [100.0 * abs(float(r["rel_error"])) for r in rs]
            fpn = sum(float(r["fibers_per_node"]) for r in rs) / len(rs)
            ax.plot(x, y, marker="o", label="k = %d (%.1f fibers / node)" % (k, fpn))
            for r, xi, yi in zip(rs, x, y):
                ax.annotate(r["nodes"], (xi, yi), fontsize=6, xytext=(3, 3), textcoords="offset points")
        ax.axhline(5.0, color="grey", linestyle="--", linewidth=1)
        ax.text(0.01, 5.2, "unit-test tolerance 5%", fontsize=7, color="grey", transform=ax.get_yaxis_transform())
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("force evaluation [ms] (energy + gradient, 1 thread, fastest run)")
        ax.set_ylabel("|bending energy error| vs analytic [%]")
        ax.set_title(titles[shape], fontsize=10)
        ax.legend(fontsize=7)
    fig.suptitle("Point-sampled thin shells: node count and neighbours / fibers against bending accuracy",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print("wrote", out)


if __name__ == "__main__":
    main()
