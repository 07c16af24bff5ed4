#!/usr/bin/python3
"""Plot the FEM speed/accuracy CSV written by `bench_fem_accuracy --csv PATH`.

Usage: /usr/bin/python3 scripts/plot_fem_tradeoff.py PATH.csv [docs/fem_accuracy_tradeoff.png]
Left: static cantilever tip-deflection error against Timoshenko beam theory over the time per stiffness
assembly, one line per mesh type and integration scheme through the resolutions. Middle: free-free bending
period error (against Euler-Bernoulli and the discrete mode) and amplitude kept per period over the implicit
Euler time step. Right: wall time per simulated second over the time step.
"""
import csv
import math
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MARKERS = {"hex": "s", "tet": "^", "random": "o"}
STYLES = {"hex": "-", "tet": ":", "random": "--"}


def number(text):
    try:
        return float(text)
    except ValueError:
        return math.nan


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/fem_accuracy_tradeoff.png"
    rows = list(csv.DictReader(open(sys.argv[1])))
    statics = [r for r in rows if r["part"] == "static"]
    dynamics = [r for r in rows if r["part"] == "dynamic"]
    if not statics or not dynamics:
        sys.exit("plot_fem_tradeoff: %s lacks static or dynamic rows" % sys.argv[1])
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8))

    ax = axes[0]
    schemes = sorted({r["scheme"] for r in statics})
    colours = {s: "C%d" % i for i, s in enumerate(schemes)}
    lines = defaultdict(list)
    for r in statics:
        # Singular (NaN) or hourglassing (|error| > 100%) stiffness matrices are left out, and so is the
        # one-sample scheme on non-tetrahedral meshes (rank-deficient K_e: 6 strain rows for 3 n dofs).
        rank_deficient = r["scheme"].startswith("centroid") and r["mesh"] != "tet"
        if math.isfinite(number(r["rel_error"])) and abs(number(r["rel_error"])) <= 1.0 and not rank_deficient:
            lines[(r["mesh"], r["scheme"])].append(r)
    for (mesh, scheme), rs in sorted(lines.items()):
        rs.sort(key=lambda r: int(r["n"]))
        x = [number(r["assembly_ms"]) for r in rs]
        y = [100.0 * abs(number(r["rel_error"])) for r in rs]
        ax.plot(x, y, marker=MARKERS.get(mesh, "x"), linestyle=STYLES.get(mesh, "-"), color=colours[scheme],
                label="%s, %s" % (mesh, scheme), markersize=4)
        for r, xi, yi in zip(rs, x, y):
            ax.annotate("n=%s" % r["n"], (xi, yi), fontsize=6, xytext=(2, 2), textcoords="offset points")
    ax.axhline(3.0, color="grey", linestyle="--", linewidth=1)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("stiffness assembly [ms] (one thread)")
    ax.set_ylabel("|tip deflection error| vs Timoshenko [%]")
    ax.set_title("(a) cantilever: integration samples vs accuracy", fontsize=10)
    ax.legend(fontsize=5, ncol=2)

    by_mesh = defaultdict(list)
    for r in dynamics:
        by_mesh[r["mesh"]].append(r)
    ax = axes[1]
    ax2 = ax.twinx()
    for i, (mesh, rs) in enumerate(sorted(by_mesh.items())):
        rs.sort(key=lambda r: number(r["dt"]))
        dt = [number(r["dt"]) for r in rs]
        analytic = [100.0 * (number(r["period"]) / number(r["analytic_period"]) - 1.0) for r in rs]
        discrete = [100.0 * (number(r["period"]) / number(r["discrete_period"]) - 1.0) for r in rs]
        theory = [100.0 * (number(r["predicted_period"]) / number(r["discrete_period"]) - 1.0) for r in rs]
        decay = [number(r["decay_per_period"]) for r in rs]
        ax.plot(dt, analytic, marker=MARKERS.get(mesh, "x"), color="C%d" % i,
                label="%s: period vs Euler-Bernoulli" % mesh)
        ax.plot(dt, discrete, marker=MARKERS.get(mesh, "x"), color="C%d" % i, linestyle="--",
                label="%s: period vs discrete mode" % mesh)
        ax.plot(dt, theory, color="C%d" % i, linestyle=":", label="%s: backward Euler theory" % mesh)
        ax2.plot(dt, decay, marker=MARKERS.get(mesh, "x"), color="C%d" % (i + 4),
                 label="%s: amplitude kept per period" % mesh)
    ax.set_xscale("log")
    ax.set_xlabel("implicit Euler time step dt [s]")
    ax.set_ylabel("period error [%]")
    ax2.set_ylabel("amplitude after one period / initial")
    ax2.set_ylim(0.0, 1.05)
    ax.set_title("(b) free-free beam: time step vs period and decay", fontsize=10)
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=6, loc="upper left")

    ax = axes[2]
    for i, (mesh, rs) in enumerate(sorted(by_mesh.items())):
        dt = [number(r["dt"]) for r in rs]
        cost = [number(r["seconds_per_simulated_second"]) for r in rs]
        ax.plot(dt, cost, marker=MARKERS.get(mesh, "x"), color="C%d" % i,
                label="%s (%s dofs)" % (mesh, rs[0]["dofs"]))
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("implicit Euler time step dt [s]")
    ax.set_ylabel("wall time per simulated second [s]")
    ax.set_title("(b) cost of the time step", fontsize=10)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print("wrote", out)


if __name__ == "__main__":
    main()
