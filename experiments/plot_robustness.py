"""Plot of exp_robustness: closest-hit mismatches with the exact oracle per method and
adversarial case (false hits + missed hits + wrong first hits), as a heat table."""
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402


def plot(out: pathlib.Path) -> None:
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
    fig, ax = plt.subplots(figsize=(1.0 + 0.9 * len(accels), 1.0 + 0.45 * len(groups)))
    im = ax.imshow(rate, cmap="Reds", vmin=0, vmax=max(1.0, rate.max()), aspect="auto")
    ax.set_xticks(range(len(accels)), accels, rotation=45, ha="right")
    ax.set_yticks(range(len(groups)), groups)
    for i in range(len(groups)):
        for j in range(len(accels)):
            ax.text(j, i, f"{rate[i, j]:.1f}" if rate[i, j] else "0", ha="center", va="center", fontsize=7)
    fig.colorbar(im, ax=ax, label="% of rays mismatching the exact oracle")
    ax.set_title("Where methods fail: mismatches with the exact oracle")
    fig.tight_layout()
    fig.savefig(out / "robustness.png", dpi=120)
    plt.close(fig)
