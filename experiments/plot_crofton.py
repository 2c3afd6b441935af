"""Plot of exp_crofton: mean projected (silhouette) area over S/4 for convex and non-convex bodies, and the
hit probability of a convex body inside another against S_o/S_c."""
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402


def plot(out: pathlib.Path) -> None:
    csv = out / "crofton.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(14, 7), gridspec_kw={"width_ratios": [1.6, 1]})
    parts = [("convex", "convex: hulls and polytopes (projections)", "tab:blue", "o"),
             ("hull_by_lines", "convex: hulls (isotropic lines)", "tab:green", "s"),
             ("nonconvex", "non-convex demo meshes (isotropic lines)", "tab:red", "D")]
    labels = []
    y = 0
    for part, label, color, marker in parts:
        g = df[df["part"] == part]
        ys = np.arange(y, y + len(g))
        ax.errorbar(g["ratio"], ys, xerr=2 * g["ratio_std_error"], fmt=marker, color=color, markersize=4,
                    linestyle="none", label=label)
        labels += list(g["body"])
        y += len(g) + 1
        labels.append("")
    ax.axvline(1.0, color="black", linewidth=0.8)
    ax.set_yticks(range(len(labels)))
    ax.set_yticklabels(labels, fontsize=6)
    ax.invert_yaxis()
    ax.set_xlabel("mean projected area / (S/4)  (error bars: 2 s.e.)")
    ax.set_title("Crofton: mean projected area is S/4 for convex bodies only", fontsize=9)
    ax.grid(True, axis="x", alpha=0.3)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=3)

    g = df[df["part"] == "nested"]
    if not g.empty:
        cmap = plt.get_cmap("tab10")
        for i, (_, r) in enumerate(g.iterrows()):
            bx.errorbar([r["predicted"]], [r["measured"]], yerr=[2 * r["std_error"]], fmt="osD^v"[i % 5],
                        color=cmap(i), markersize=5, linestyle="none", label=r["body"])
        lo, hi = g["predicted"].min() / 2, 1.0
        bx.plot([lo, hi], [lo, hi], color="black", linewidth=0.8, label="measured = S_o/S_c")
        bx.set_xscale("log")
        bx.set_yscale("log")
        bx.set_xlabel("S_o / S_c (surface areas)")
        bx.set_ylabel("P(line meets inner | line meets outer)")
        bx.set_title("Convex within convex: isotropic lines", fontsize=9)
        bx.grid(True, which="both", alpha=0.3)
        bx.legend(fontsize=6, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=1,
                  title="inner in outer (error bars: 2 s.e.)", title_fontsize=6)
    fig.tight_layout()
    fig.savefig(out / "crofton.png", dpi=110)
    plt.close(fig)
