"""Plots of exp_robustness: closest-hit mismatches with the exact oracle per method and
adversarial case (false hits + missed hits + wrong first hits) as a heat table, with the
mismatches per contact class beside it; and the cost of certainty: single-thread throughput of
the BVH's fast, robust and certified paths next to Embree and Embree robust."""
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

CLASSES = ["crossing", "touching", "on_surface", "ill_conditioned"]


def plot_mismatches(out: pathlib.Path) -> None:
    """A heat table, one row per method: the share of rays mismatching per case group, then per contact
    class (robustness.csv's class columns, summed over the cases: the per-class table's numbers)."""
    csv = out / "robustness.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)
    df["group"] = df["case"].where(~df["case"].str.startswith("shared_edges/") | (df["case"] == "shared_edges/fan256"),
                                   "shared_edges/cgal")
    agg = df.groupby(["group", "accel"], sort=False)[["mismatches", "rays"]].sum().reset_index()
    groups = list(dict.fromkeys(agg["group"]))
    accels = list(dict.fromkeys(agg["accel"]))
    rate = np.zeros((len(accels), len(groups)))
    for _, r in agg.iterrows():
        rate[accels.index(r["accel"]), groups.index(r["group"])] = 100.0 * r["mismatches"] / max(1, r["rays"])
    columns = list(groups)
    table = rate
    if "rays_crossing" in df.columns:
        sums = df.groupby("accel", sort=False)[[f"{k}_{c}" for c in CLASSES for k in ("rays", "mismatches")]].sum()
        per_class = np.array([[100.0 * sums.loc[a, f"mismatches_{c}"] / sums.loc[a, f"rays_{c}"]
                               if sums.loc[a, f"rays_{c}"] else np.nan for c in CLASSES] for a in accels])
        table = np.hstack([rate, np.full((len(accels), 1), np.nan), per_class])
        columns = groups + [""] + [f"class: {c} ({int(sums[f'rays_{c}'].iloc[0])} rays)" for c in CLASSES]
    fig, ax = plt.subplots(figsize=(3.5 + 0.62 * len(columns), 1.8 + 0.2 * len(accels)))
    im = ax.imshow(table, cmap="Reds", vmin=0, vmax=100, aspect="auto")
    ax.set_yticks(range(len(accels)), accels, fontsize=7)
    ax.set_xticks(range(len(columns)), columns, rotation=35, ha="right", fontsize=8)
    ax.xaxis.tick_top()
    plt.setp(ax.get_xticklabels(), ha="left", rotation=35)
    for i in range(len(accels)):
        for j in range(table.shape[1]):
            v = table[i, j]
            if not np.isnan(v):
                text = "0" if v == 0 else f"{v:.0f}" if v >= 10 else f"{v:.2g}"
                ax.text(j, i, text, ha="center", va="center", fontsize=6.5, color="white" if v > 60 else "black")
    fig.colorbar(im, ax=ax, label="% of rays mismatching the exact oracle (0-100)", shrink=0.5, pad=0.02)
    ax.set_xlabel("Where methods fail: share of rays mismatching the exact oracle, per case (left) and per contact "
                  "class over every case (right); blank: no ray of the class", fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "robustness.png", dpi=100)
    plt.close(fig)


def plot_certainty(out: pathlib.Path) -> None:
    csv = out / "certainty.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)
    paths = ["embree", "embree-robust", "bvh:robust=off", "bvh:kernel=watertight", "bvh"]
    df = df[df["accel"].isin(paths) & df["rays"].isin(["primary", "diffuse", "shadow"])]
    if df.empty:
        return
    cases = list(dict.fromkeys(zip(df["scene"], df["rays"])))
    fig, ax = plt.subplots(figsize=(2.0 + 1.3 * len(cases), 4.0))
    width = 0.8 / len(paths)
    for k, p in enumerate(paths):
        rows = [df[(df["scene"] == s) & (df["rays"] == r) & (df["accel"] == p)].iloc[0] for s, r in cases]
        values = np.array([row["mrays_per_s"] for row in rows], float)
        errors = None
        if "ns_per_ray_lo" in df.columns:  # the 95% interval of the median time, as throughput
            low = np.array([1e3 / row["ns_per_ray_hi"] for row in rows], float)
            high = np.array([1e3 / row["ns_per_ray_lo"] for row in rows], float)
            errors = [np.maximum(values - low, 0), np.maximum(high - values, 0)]
        ax.bar(np.arange(len(cases)) + (k - (len(paths) - 1) / 2) * width, values, width, label=p, yerr=errors,
               capsize=2, error_kw={"linewidth": 0.8})
    ax.set_xticks(range(len(cases)), [f"{s}\n{r}" for s, r in cases], fontsize=7)
    ax.set_ylabel("million rays per second, 1 thread")
    ax.set_title("The cost of certainty: fast, watertight and certified (default) BVH against Embree\n"
                 "(bars: medians over the rounds; whiskers: 95% intervals)", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "certainty.png", dpi=120)
    plt.close(fig)


def plot(out: pathlib.Path) -> None:
    plot_mismatches(out)
    plot_certainty(out)
