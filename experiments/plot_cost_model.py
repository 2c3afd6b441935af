"""Plots of exp_cost_model: predicted against measured ns per ray on the held-out scenes for the
counters model, the tree model and plain SAH at 1:80 and 1:1.5; the fitted per-event constants
with their standard errors; trees built from the fitted model against the textbook ratios; and
(cost_memory.png) ns per node visit against triangles and structure bytes, measured and as the
counters model predicts it, per structure family."""
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402


def _scatter(ax, h, column, title):
    measured = h["measured_ns"].to_numpy(float)
    lo, hi = max(1.0, measured.min() / 2), measured.max() * 2
    for family, g in h.groupby("family"):
        ax.scatter(g["measured_ns"], g[column].clip(lower=lo / 2), s=8, alpha=0.7, label=family)
    ax.plot([lo, hi], [lo, hi], color="black", linewidth=0.8, label="predicted = measured")
    for f in (0.85, 1.15):
        ax.plot([lo, hi], [lo * f, hi * f], color="gray", linewidth=0.6, linestyle=":")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo / 2, hi * 2)
    ape = np.abs(h[column].to_numpy(float) - measured) / measured
    ax.set_title(f"{title}: MAPE {100 * ape.mean():.1f}%", fontsize=9)
    ax.set_xlabel("measured ns per ray (held-out scenes)")
    ax.set_ylabel("predicted ns per ray")
    ax.grid(True, which="both", alpha=0.2)


def _half_decade_medians(g, x_column, y_column):
    """Medians of y per half decade of x, at the bins' geometric middles."""
    x = np.log10(g[x_column].to_numpy(float))
    y = g[y_column].to_numpy(float)
    bins = np.floor(2 * x)
    xs, ys = [], []
    for b in np.unique(bins):
        sel = bins == b
        xs.append(10 ** ((b + 0.5) / 2))
        ys.append(np.median(y[sel]))
    return np.array(xs), np.array(ys)


def plot_memory(out: pathlib.Path) -> None:
    csv = out / "cost_memory.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)
    df = df[(df["measured_ns_per_visit"] > 0) & (df["counters_ns_per_visit"] > 0) & (df["primitives"] > 0)]
    if df.empty:
        return
    fig, axes = plt.subplots(1, 2, figsize=(14, 5.5), sharey=True)
    families = sorted(df["family"].unique())[:10]  # 10 families + 2 style entries: at most 12 legend entries
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, x_column, label in ((axes[0], "primitives", "triangles"), (axes[1], "bytes", "structure bytes")):
        for k, family in enumerate(families):
            g = df[df["family"] == family]
            color = colors[k % len(colors)]
            ax.scatter(g[x_column], g["measured_ns_per_visit"], s=6, alpha=0.35, color=color)
            xs, ys = _half_decade_medians(g, x_column, "counters_ns_per_visit")
            ax.plot(xs, ys, color=color, linewidth=1.6, label=family if ax is axes[0] else None)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(label)
        ax.grid(True, which="both", alpha=0.2)
    for size, name in ((df["l2_bytes"].max(), "L2"), (df["llc_bytes"].max(), "last-level cache")):
        if size > 0:
            axes[1].axvline(size, color="black", linestyle=":", linewidth=0.9)
            axes[1].annotate(name, (size, 0.97), xycoords=("data", "axes fraction"), fontsize=7, rotation=90,
                             ha="right", va="top")
    axes[0].set_ylabel("ns per node visit (nodes + leaves)")
    axes[0].scatter([], [], s=6, color="gray", label="measured (one point per row)")
    axes[0].plot([], [], color="gray", linewidth=1.6, label="counters model (median per half decade)")
    axes[0].legend(fontsize=7, loc="upper left")
    axes[0].set_title("time per node visit against scene size", fontsize=9)
    axes[1].set_title("against structure size and this machine's caches", fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "cost_memory.png", dpi=110)
    plt.close(fig)


def plot(out: pathlib.Path) -> None:
    plot_memory(out)
    csv = out / "cost_model.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)
    h = df[df["part"] == "heldout"]
    fig, axes = plt.subplots(2, 3, figsize=(16, 10))
    if len(h):
        _scatter(axes[0][0], h, "counters_ns", "counters model")
        _scatter(axes[0][1], h, "tree_ns", "tree model")
        _scatter(axes[1][0], h, "sah80_ns", "plain SAH 1:80, scaled")
        _scatter(axes[1][1], h, "sah15_ns", "plain SAH 1:1.5, scaled")
        axes[0][0].legend(fontsize=6, loc="upper left")
    c = df[(df["part"] == "constants") & (df["level"] == "counters") & df["term"].isin(["node", "leaf", "test"])]
    if len(c):
        ax = axes[0][2]
        families = sorted(c["family"].unique())
        width = 0.27
        for k, term in enumerate(["node", "leaf", "test"]):
            g = c[c["term"] == term].set_index("family").reindex(families)
            x = np.arange(len(families)) + (k - 1) * width
            ax.bar(x, g["value"].to_numpy(float), width, yerr=g["std_error"].fillna(0).to_numpy(float), capsize=2,
                   label=f"c_{term}")
        ax.set_xticks(np.arange(len(families)))
        ax.set_xticklabels(families, rotation=30, fontsize=7)
        ax.set_ylabel("ns per event (± 1 standard error)")
        ax.set_title("counters model: fitted constants", fontsize=9)
        ax.legend(fontsize=7)
        ax.grid(True, axis="y", alpha=0.3)
    # builders rows: measured_ns is the cost=model tree, counters_ns the 1:80 tree, tree_ns the 1:1.5 tree.
    b = df[df["part"] == "builders"]
    if len(b):
        ax = axes[1][2]
        labels = [f"{r.scene[:18]} {r.rays} {r.family}" for r in b.itertuples()]
        cost = b["measured_ns"].to_numpy(float)
        best = np.minimum(b["counters_ns"].to_numpy(float), b["tree_ns"].to_numpy(float))
        y = np.arange(len(b))
        ax.barh(y, best / cost)
        ax.axvline(1.0, color="black", linewidth=0.8)
        ax.axvline(0.98, color="gray", linewidth=0.8, linestyle=":")
        ax.set_yticks(y)
        ax.set_yticklabels(labels, fontsize=5)
        ax.set_xlabel("speed-up of cost=model over the faster of 1:80 and 1:1.5")
        ax.set_title("trees built from the fitted model (held-out scenes)", fontsize=9)
        ax.grid(True, axis="x", alpha=0.3)
    for ax in axes.flat:
        if not ax.has_data():
            ax.set_visible(False)
    fig.tight_layout()
    fig.savefig(out / "cost_model.png", dpi=110)
    plt.close(fig)
