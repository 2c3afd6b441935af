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

BUCKETS = ["crossing", "touching", "on_surface", "ill_conditioned"]


def plot_mismatches(out: pathlib.Path) -> None:
    csv = out / "robustness.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)
    df["group"] = df["case"].where(~df["case"].str.startswith("shared_edges/") | (df["case"] == "shared_edges/fan256"),
                                   "shared_edges/cgal")
    agg = df.groupby(["group", "accel"], sort=False)[["mismatches", "rays"]].sum().reset_index()
    groups = list(dict.fromkeys(agg["group"]))
    accels = list(dict.fromkeys(agg["accel"]))
    rate = np.zeros((len(groups), len(accels)))
    for _, r in agg.iterrows():
        rate[groups.index(r["group"]), accels.index(r["accel"])] = 100.0 * r["mismatches"] / max(1, r["rays"])
    per_class = None
    if "rays_crossing" in df.columns:
        sums = df.groupby("accel", sort=False)[[f"{k}_{b}" for b in BUCKETS for k in ("rays", "mismatches")]].sum()
        per_class = np.array([[100.0 * sums.loc[a, f"mismatches_{b}"] / max(1, sums.loc[a, f"rays_{b}"]) for a in accels]
                              for b in BUCKETS])
    rows = len(groups) + (len(BUCKETS) + 1 if per_class is not None else 0)
    fig, ax = plt.subplots(figsize=(1.0 + 0.45 * len(accels), 1.5 + 0.42 * rows))
    table = rate if per_class is None else np.vstack([rate, np.full((1, len(accels)), np.nan), per_class])
    labels = groups if per_class is None else groups + [""] + [f"class: {b}" for b in BUCKETS]
    im = ax.imshow(table, cmap="Reds", vmin=0, vmax=max(1.0, np.nanmax(table)), aspect="auto")
    ax.set_xticks(range(len(accels)), accels, rotation=60, ha="right", fontsize=6)
    ax.set_yticks(range(len(labels)), labels, fontsize=7)
    for i in range(table.shape[0]):
        for j in range(len(accels)):
            if not np.isnan(table[i, j]):
                ax.text(j, i, f"{table[i, j]:.1f}" if table[i, j] else "0", ha="center", va="center", fontsize=5)
    fig.colorbar(im, ax=ax, label="% of rays mismatching the exact oracle")
    ax.set_title("Where methods fail: mismatches with the exact oracle, per case and per contact class")
    fig.tight_layout()
    fig.savefig(out / "robustness.png", dpi=120)
    plt.close(fig)


def plot_certainty(out: pathlib.Path) -> None:
    csv = out / "certainty.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)
    paths = ["embree", "embree-robust", "bvh:robust=off", "bvh", "bvh:kernel=certified"]
    df = df[df["accel"].isin(paths) & df["rays"].isin(["primary", "diffuse", "shadow"])]
    if df.empty:
        return
    cases = list(dict.fromkeys(zip(df["scene"], df["rays"])))
    fig, ax = plt.subplots(figsize=(2.0 + 1.3 * len(cases), 4.0))
    width = 0.8 / len(paths)
    for k, p in enumerate(paths):
        values = [df[(df["scene"] == s) & (df["rays"] == r) & (df["accel"] == p)]["mrays_per_s"].max() for s, r in cases]
        ax.bar(np.arange(len(cases)) + (k - (len(paths) - 1) / 2) * width, values, width, label=p)
    ax.set_xticks(range(len(cases)), [f"{s}\n{r}" for s, r in cases], fontsize=7)
    ax.set_ylabel("million rays per second, 1 thread")
    ax.set_title("The cost of certainty: fast, robust and certified BVH against Embree")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "certainty.png", dpi=120)
    plt.close(fig)


def plot(out: pathlib.Path) -> None:
    plot_mismatches(out)
    plot_certainty(out)
