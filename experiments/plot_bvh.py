"""Plots of exp_bvh: the lecture's BVH-versus-kd-tree comparison, rotated walls, the time shares as
scenes grow, and throughput relative to Embree."""
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402


def plot(out: pathlib.Path) -> None:
    csv = out / "bvh.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)
    fig, axes = plt.subplots(2, 2, figsize=(13, 9))

    t = df[df["part"] == "table"]
    if len(t):
        ax = axes[0][0]
        labels = [f"{s.split(',')[0][:20]}\n{a}" for s, a in zip(t["scene"], t["accel"])]
        x = np.arange(len(t))
        ax.bar(x - 0.2, t["tests_per_ray"], width=0.4, label="tests / ray")
        ax2 = ax.twinx()
        ax2.bar(x + 0.2, 100 * t["hits_per_test"], width=0.4, color="tab:orange", label="hit rate %")
        ax.set_xticks(x)
        ax.set_xticklabels(labels, fontsize=6, rotation=30, ha="right")
        ax.set_ylabel("ray/triangle tests per ray")
        ax2.set_ylabel("tests that hit (%)")
        ax.set_title("BVH vs kd-tree: tests and hit rate (pbrt: 4.75x tests, 4.1% vs 16%)", fontsize=9)
        ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.08), fontsize=7)
        ax2.legend(loc="lower right", bbox_to_anchor=(1.0, 1.08), fontsize=7)

    w = df[df["part"] == "walls"]
    curves = pd.read_csv(out / "bvh_walls_fit.csv") if (out / "bvh_walls_fit.csv").exists() else None
    if len(w):
        ax = axes[0][1]
        cmap = plt.get_cmap("tab10")
        for i, (accel, g) in enumerate(w.groupby("accel", sort=False)):
            g = g.assign(angle=g["param"].astype(float)).sort_values("angle")
            if "ns_per_ray_lo" in g:  # medians of replicate rounds with their 95% intervals
                ns = g["ns_per_ray"].to_numpy(float)
                ax.errorbar(g["angle"], ns, yerr=[ns - g["ns_per_ray_lo"].to_numpy(float), g["ns_per_ray_hi"].to_numpy(float) - ns],
                            marker="o", linestyle="none", capsize=2, color=cmap(i), label=f"{accel} (median, 95% interval)")
            else:
                ax.plot(g["angle"], g["ns_per_ray"], marker="o", linestyle="none", color=cmap(i), label=accel)
            if curves is not None:
                c = curves[curves["accel"] == accel]
                ax.plot(c["angle"], c["fitted_ns_per_ray"], color=cmap(i), linewidth=1,
                        label=f"{accel}: fit a + b·(box growth)")
        ax.set_xlabel("wall rotation (degrees)")
        ax.set_ylabel("ns / ray (1 thread)")
        ax.set_title("rotated walls (pbrt: 4.19x slower rotated)", fontsize=9)
        ax.legend(fontsize=6, loc="upper left", bbox_to_anchor=(1.01, 1.0))
        ax.grid(True, alpha=0.3)

    s = df[df["part"] == "shares"]
    if len(s):
        ax = axes[1][0]
        x = np.arange(len(s))
        ax.bar(x, 100 * s["traversal_share"], label="traversal (ours)")
        ax.bar(x, 100 * s["tri_share"], bottom=100 * s["traversal_share"], label="triangle tests (ours)")
        lecture = {3.02e5: 27.4 / (27.4 + 10.2), 4.83e6: 42.7 / (42.7 + 13.3), 3.11e9: 74.7 / (74.7 + 13.3)}
        nearest = [min(lecture, key=lambda k: abs(np.log(k / n))) for n in s["triangles"]]
        ax.plot(x, [100 * lecture[k] for k in nearest], "k^", label="lecture: accel / (accel + tri)")
        ax.set_xticks(x)
        ax.set_xticklabels([f"{a}\n{n:.3g} tris" for a, n in zip(s["accel"], s["triangles"])], fontsize=7)
        ax.set_ylabel("% of ray-shooting time")
        ax.set_title("where time goes as scenes grow (diffuse rays)", fontsize=9)
        ax.legend(fontsize=7, loc="lower left", bbox_to_anchor=(0.0, 1.08), ncol=3)

    axes[1][1].axis("off")  # throughput against Embree: its own figure, bvh_embree.png
    fig.tight_layout()
    fig.savefig(out / "bvh.png", dpi=110)
    plt.close(fig)
    plot_against_embree(df, out)


def plot_against_embree(df: pd.DataFrame, out: pathlib.Path) -> None:
    """Throughput over Embree per scene (rows) and ray kind x comparison (columns), single thread:
    one annotated cell per ratio, so no label covers another."""
    p = df[(df["part"] == "speed") & (df["threads"] == 1)]
    if not len(p):
        return
    p = p.assign(kind=p["ray_spec"].str.split(":").str[0])
    comparisons = [("bvh", "throughput_vs_embree_robust", "bvh / embree-robust"),
                   ("bvh:robust=off", "throughput_vs_embree", "robust=off / embree"),
                   ("bvh", "throughput_vs_embree", "bvh / embree"),
                   ("bvh", "own_loop_vs_embree_direct", "bvh direct / embree-robust direct")]
    scenes = list(dict.fromkeys(p["scene"]))
    kinds = [k for k in ("primary", "diffuse", "shadow") if k in set(p["kind"])]
    grid = np.full((len(scenes), len(kinds) * len(comparisons)), np.nan)
    labels = []
    for k, kind in enumerate(kinds):
        for c, (accel, column, label) in enumerate(comparisons):
            labels.append(f"{kind}: {label}")
            for r, scene in enumerate(scenes):
                row = p[(p["scene"] == scene) & (p["kind"] == kind) & (p["accel"] == accel)]
                if len(row) and row[column].iloc[0] > 0:
                    grid[r, k * len(comparisons) + c] = row[column].iloc[0]
    fig, ax = plt.subplots(figsize=(1.0 + 0.75 * grid.shape[1], 1.8 + 0.5 * len(scenes)))
    image = ax.imshow(grid, cmap="RdBu", vmin=0.5, vmax=1.5, aspect="auto")
    for r in range(grid.shape[0]):
        for c in range(grid.shape[1]):
            if not np.isnan(grid[r, c]):
                ax.text(c, r, f"{grid[r, c]:.2f}", ha="center", va="center", fontsize=7)
    for k in range(1, len(kinds)):
        ax.axvline(k * len(comparisons) - 0.5, color="k", linewidth=1.5)
    ax.set_xticks(range(grid.shape[1]))
    ax.set_xticklabels(labels, rotation=40, ha="right", fontsize=7)
    ax.set_yticks(range(len(scenes)))
    ax.set_yticklabels([s if len(s) <= 32 else s[:30] + "…" for s in scenes], fontsize=7)
    ax.set_title("BVH throughput / Embree's, single thread (> 1: faster than Embree; blank: not measured)", fontsize=9)
    fig.colorbar(image, ax=ax, fraction=0.03, pad=0.01)
    fig.tight_layout()
    fig.savefig(out / "bvh_embree.png", dpi=110)
    plt.close(fig)
