"""Plot of exp_speed_accuracy: one chart per scene family, each method one point, throughput relative to
Embree against the error rate on random, edge-aimed and vertex-aimed rays. Errors span decades, so the
error axis is logarithmic, with a separate band on its left for methods with no error at all."""
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

MARKERS = ["o", "s", "^", "v", "D", "P", "X", "<", ">", "*", "h", "p", "d", "8"]


def _styles(methods):
    """A colour per accelerator kind, a marker per variant within it."""
    kinds = list(dict.fromkeys(m.split(":")[0] for m in methods))
    cmap = plt.get_cmap("tab10")
    seen = {}
    styles = {}
    for m in methods:
        k = m.split(":")[0]
        i = seen.get(k, 0)
        seen[k] = i + 1
        styles[m] = (cmap(kinds.index(k) % 10), MARKERS[i % len(MARKERS)])
    return styles


def plot(out: pathlib.Path) -> None:
    csv = out / "speed_accuracy.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)
    allrows = df[df["rays"] == "all"]
    families = list(dict.fromkeys(allrows["family"]))
    methods = list(dict.fromkeys(allrows["method"]))
    styles = _styles(methods)
    rates = allrows["error_rate"].to_numpy(float)
    positive = rates[rates > 0]
    lo = 10 ** np.floor(np.log10(positive.min())) if len(positive) else 1e-4
    zero_x = lo / 4  # the "0" band sits left of the smallest error on the log axis
    ncols = 2
    nrows = (len(families) + 1) // 2
    fig, axes = plt.subplots(nrows, ncols, figsize=(15, 5.2 * nrows), squeeze=False)
    rng = np.random.default_rng(1)
    for idx, fam in enumerate(families):
        ax = axes[idx // ncols][idx % ncols]
        g = allrows[allrows["family"] == fam]
        for _, r in g.iterrows():
            color, marker = styles[r["method"]]
            x = r["error_rate"] if r["error_rate"] > 0 else zero_x * (1 + 0.5 * (rng.random() - 0.5))
            ax.scatter([x], [r["throughput_vs_embree"]], color=color, marker=marker, s=36, edgecolors="black",
                       linewidths=0.3, label=r["method"], zorder=3)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.axvspan(zero_x / 2, zero_x * 2, color="0.9", zorder=0)
        xmax = max(1.0, positive.max() * 2) if len(positive) else 1.0
        ax.set_xlim(zero_x / 2, xmax)
        ticks = [zero_x] + [10.0 ** e for e in range(int(np.log10(lo)), int(np.ceil(np.log10(xmax))) + 1)]
        ax.set_xticks(ticks)
        ax.set_xticklabels(["0"] + [f"{t:g}" for t in ticks[1:]])
        ax.axhline(1.0, color="black", linewidth=0.6, linestyle=":")
        ax.set_xlabel("error rate: share of rays whose closest hit differs from `exact` (grey band: no error)", fontsize=9)
        ax.set_ylabel("throughput relative to Embree (1 thread, same rays)")
        ax.set_title(f"{fam}: {g['scene'].iloc[0]}", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    for idx in range(len(families), nrows * ncols):
        axes[idx // ncols][idx % ncols].set_visible(False)
    handles = {}
    for ax in axes.flat:
        for h, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, h)
    fig.legend(handles.values(), handles.keys(), loc="center left", bbox_to_anchor=(0.79, 0.5), fontsize=7,
               title="method (as `raylab accels` names it)", title_fontsize=7, ncol=1)
    fig.tight_layout(rect=(0, 0, 0.78, 1))
    fig.savefig(out / "speed_accuracy.png", dpi=110)
    plt.close(fig)
