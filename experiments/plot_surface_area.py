"""Plot of exp_surface_area: cells met by isotropic lines against the surface-area prediction, and the
ratio of real traversals' visits to it per ray kind."""
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from figures import legend_outside  # noqa: E402


def plot(out: pathlib.Path) -> None:
    csv = out / "surface_area.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(14, 5.5))
    geo = df[df["part"] == "lines_geometric"]
    markers = {"interior visits": "o", "leaf visits": "s", "primitive tests": "^"}
    cmap = plt.get_cmap("tab10")
    accels = list(dict.fromkeys(geo["accel"]))
    for i, accel in enumerate(accels):
        for q, m in markers.items():
            g = geo[(geo["accel"] == accel) & (geo["quantity"] == q)]
            ax.errorbar(g["predicted"], g["measured"], yerr=2 * g["std_error"], fmt=m, color=cmap(i), markersize=4,
                        linestyle="none")
    # One legend entry per structure (colour) and per quantity (marker), not per pair: at most 12.
    for i, accel in enumerate(accels):
        ax.plot([], [], color=cmap(i), marker="o", markersize=4, linestyle="none", label=accel)
    for q, m in markers.items():
        ax.plot([], [], color="grey", marker=m, markersize=4, linestyle="none", label=q)
    lo = max(0.5, geo[["predicted", "measured"]].min().min() / 1.5)
    hi = geo[["predicted", "measured"]].max().max() * 1.5
    ax.plot([lo, hi], [lo, hi], color="black", linewidth=0.8, label="measured = predicted")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("predicted per line: Σ SA(cell)/SA(root) (visits) or Σ N·SA/SA(root) (tests)")
    ax.set_ylabel("measured per line meeting the root (error bars: 2 s.e.)")
    ax.set_title("Isotropic lines, no early exit: cells met against the surface-area prediction", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    legend_outside(ax, fontsize=6)

    tr = df[(df["part"] == "traversal") & (df["quantity"] == "interior visits")].copy()
    if not tr.empty:
        tr["kind"] = tr["rays"].str.split(":").str[0]
        kinds = list(dict.fromkeys(tr["kind"]))
        accels = list(dict.fromkeys(tr["accel"]))
        width = 0.8 / len(kinds)
        x = np.arange(len(accels))
        for j, kind in enumerate(kinds):
            g = tr[tr["kind"] == kind].groupby("accel")["ratio"].agg(["mean", "min", "max"]).reindex(accels)
            bx.bar(x + j * width, g["mean"], width, label=f"{kind} rays",
                   yerr=[g["mean"] - g["min"], g["max"] - g["mean"]], capsize=2)
        bx.axhline(1.0, color="black", linewidth=0.8)
        bx.set_xticks(x + width * (len(kinds) - 1) / 2)
        bx.set_xticklabels(accels, fontsize=8)
        bx.set_ylabel("interior visits / Σ SA(n)/SA(root)\n(mean over scenes; bars: their range)")
        bx.set_title("Real traversals (early exit, rays from inside) against the prediction", fontsize=9)
        bx.grid(True, axis="y", alpha=0.3)
        legend_outside(bx, fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "surface_area.png", dpi=110)
    plt.close(fig)
