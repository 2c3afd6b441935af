"""Plot of exp_speed_accuracy, the headline chart: one panel per scene family, each method one point,
throughput relative to Embree on ordinary rays (with its 95% interval) against the error rate on the
adversarial rays. Colour says the structure, the marker the kernel; the Pareto frontier is drawn and
its methods named. Errors span decades, so the error axis is logarithmic, with a separate band at the
bottom for methods with no error at all."""
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

# Structure families (colour). Embree is drawn in black and named by its kernel markers; `auto`
# (the cost model's pick) in grey, labelled where it is drawn.
FAMILIES = {
    "brute force, oracle": (["brute", "exact"], "tab:brown"),
    "grid, nested grid": (["grid", "nested-grid"], "tab:green"),
    "kd-tree": (["kdtree"], "tab:blue"),
    "octree": (["octree"], "tab:purple"),
    "BSP": (["bsp"], "tab:orange"),
    "BVH": (["bvh", "certified-instances"], "tab:red"),
}
EMBREE_COLOUR = "black"
AUTO_COLOUR = "0.55"

# Kernels (marker).
KERNELS = {"watertight": "o", "mt": "v", "certified": "s", "exact": "D", "Embree default": "P", "Embree robust": "X"}


def structure_colour(method: str):
    kind = method.split(":")[0]
    if kind.startswith("embree"):
        return EMBREE_COLOUR
    for _, (kinds, colour) in FAMILIES.items():
        if kind in kinds:
            return colour
    return AUTO_COLOUR


def kernel_of(method: str) -> str:
    """The kernel a method spec runs: its `kernel=` parameter, else the structure's default."""
    kind, _, params = method.partition(":")
    if kind == "embree-robust":
        return "Embree robust"
    if kind == "embree":
        return "Embree default"
    if kind == "exact":
        return "exact"
    if kind == "certified-instances":
        return "certified"
    values = dict(p.split("=", 1) for p in params.split(",") if "=" in p)
    if "kernel" in values:
        return values["kernel"]
    if values.get("robust") == "off":
        return "mt"  # the BVH's fast variant: plain slab test and Moller-Trumbore
    if values.get("accept") == "first":
        return "watertight"  # the grids' accept=first rules the certified kernel out
    return "certified"


def pareto_front(throughput, errors):
    """Indices of the points no other point beats on both axes (faster and no more errors, or as fast
    and fewer errors), fastest first."""
    order = sorted(range(len(throughput)), key=lambda i: (-throughput[i], errors[i]))
    front, best = [], np.inf
    for i in order:
        if errors[i] < best:
            front.append(i)
            best = errors[i]
    return front


def family_rows(df):
    return df[df["rays"] == "all"]


def at_a_glance(allrows):
    """The two names the chart is read for, by exp_speed_accuracy's rule: the exact method with no error
    of the highest geometric-mean throughput ratio, and the float method with the fewest errors (then the
    fastest), each with its ratio and errors over the families."""
    per = allrows.groupby("method", sort=False).agg(
        rule=("rule", "first"), errors=("mismatches", "sum"), rays=("ray_count", "sum"),
        ratio=("throughput_vs_embree", lambda v: float(np.exp(np.mean(np.log(v))))))
    exact = per[(per["rule"] == "exact") & (per["errors"] == 0)]
    floats = per[per["rule"] != "exact"].sort_values(["errors", "ratio"], ascending=[True, False], kind="stable")
    text = lambda m: f"{m} ({per.loc[m, 'ratio']:.2f}× Embree, {int(per.loc[m, 'errors'])} errors in {int(per.loc[m, 'rays'])} rays)"
    return (text(exact["ratio"].idxmax()) if not exact.empty else "none",
            text(floats.index[0]) if not floats.empty else "none")


def plot(out: pathlib.Path) -> None:
    csv = out / "speed_accuracy.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)
    if "throughput_ci95_lo" not in df.columns:
        return
    allrows = family_rows(df)
    families = list(dict.fromkeys(allrows["family"]))
    rays_per_family = allrows.groupby("family", sort=False)["ray_count"].max()
    positive = allrows["error_rate"][allrows["error_rate"] > 0]
    lo = 10 ** np.floor(np.log10(positive.min())) if len(positive) else 1e-4
    zero_y = lo / 8  # the "0 errors" band sits under the smallest error on the log axis
    y_max = max(1.0, positive.max() * 1.5) if len(positive) else 1.0
    x_min = allrows["throughput_ci95_lo"].min() / 1.6
    x_max = allrows["throughput_ci95_hi"].max() * 1.6
    ncols = 2
    nrows = (len(families) + 1) // 2
    fig, axes = plt.subplots(nrows, ncols, figsize=(13, 5.0 * nrows + 1.0), squeeze=False)
    for idx, fam in enumerate(families):
        ax = axes[idx // ncols][idx % ncols]
        g = allrows[allrows["family"] == fam].reset_index(drop=True)
        x = g["throughput_vs_embree"].to_numpy(float)
        y = np.where(g["error_rate"] > 0, g["error_rate"], zero_y)
        ax.axhspan(zero_y / 2.2, zero_y * 2.2, color="0.9", zorder=0)
        for i, r in g.iterrows():
            colour = structure_colour(r["method"])
            ax.errorbar([x[i]], [y[i]],
                        xerr=[[x[i] - r["throughput_ci95_lo"]], [r["throughput_ci95_hi"] - x[i]]],
                        fmt=KERNELS[kernel_of(r["method"])], color=colour, markersize=6, markeredgecolor="black",
                        markeredgewidth=0.4, elinewidth=0.7, capsize=0, zorder=3)
            if colour == AUTO_COLOUR:
                ax.annotate(r["method"], (x[i], y[i]), xytext=(4, -9), textcoords="offset points", fontsize=7,
                            color="0.35")
        front = pareto_front(x, g["mismatches"].to_numpy(float))
        fx, fy = x[front], y[front]
        ax.step(fx, fy, where="post", color="black", linewidth=0.8, alpha=0.7, zorder=2)
        # Frontier labels in a column in the empty upper middle of the panel, each tied to its point
        # (the fast methods crowd near Embree).
        for k, i in enumerate(front):
            ax.annotate(g["method"][i], (x[i], y[i]), xytext=(0.42, 0.95 - 0.065 * k), textcoords="axes fraction",
                        fontsize=8, fontweight="bold", ha="right", va="center",
                        arrowprops=dict(arrowstyle="-", color="0.4", linewidth=0.6, shrinkA=0, shrinkB=3),
                        bbox=dict(boxstyle="round,pad=0.15", facecolor="white", edgecolor="none", alpha=0.85))
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(x_min, x_max)
        ax.set_ylim(zero_y / 2.2, y_max)
        decades = range(int(np.log10(lo)), int(np.ceil(np.log10(y_max))) + 1)
        ticks = [zero_y] + [10.0 ** e for e in decades]
        ax.set_yticks(ticks)
        ax.set_yticklabels([f"0 in {int(rays_per_family[fam])}"] + [f"{t:g}" for t in ticks[1:]], fontsize=9)
        ax.minorticks_off()
        ax.axvline(1.0, color="black", linewidth=0.6, linestyle=":")
        ax.set_xlabel("throughput ÷ Embree's on primary, diffuse, shadow rays (1 thread; bars: 95% interval)",
                      fontsize=9)
        ax.set_ylabel("error rate on adversarial rays (share of rays)", fontsize=9)
        ax.set_title(f"{fam}: {g['scene'].iloc[0]}", fontsize=10)
        ax.grid(True, which="major", alpha=0.3)
    for idx in range(len(families), nrows * ncols):
        axes[idx // ncols][idx % ncols].set_visible(False)
    fastest_exact, most_accurate_float = at_a_glance(allrows)
    fig.suptitle(f"Fastest exact method: {fastest_exact}\nMost accurate float method: {most_accurate_float}",
                 fontsize=11, fontweight="bold")
    structure_handles = [Line2D([], [], linestyle="none", marker="o", color=c, markeredgecolor="black",
                                markeredgewidth=0.4, label=name) for name, (_, c) in FAMILIES.items()]
    kernel_handles = [Line2D([], [], linestyle="none", marker=m, color=EMBREE_COLOUR if k.startswith("Embree") else "white",
                             markeredgecolor="black", label=k) for k, m in KERNELS.items()]
    fig.legend(handles=structure_handles, loc="lower left", bbox_to_anchor=(0.06, 0.0), ncol=6, fontsize=9,
               title="colour: structure (grey: auto, labelled)", title_fontsize=9, frameon=False)
    fig.legend(handles=kernel_handles, loc="lower right", bbox_to_anchor=(0.98, 0.0), ncol=3, fontsize=9,
               title="marker: kernel", title_fontsize=9, frameon=False)
    fig.tight_layout(rect=(0, 0.08, 1, 0.95))
    fig.savefig(out / "speed_accuracy.png", dpi=100)
    plt.close(fig)
