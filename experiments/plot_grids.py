"""Plots of exp_grids: time and primitive tests per ray against the grid density d (with Embree's
time for reference), and uniform/nested/two-level grids against Embree on each scene."""
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from figures import draw_fit, fit_row, legend_outside, read_fits  # noqa: E402


def plot(out: pathlib.Path) -> None:
    csv = out / "grids.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)

    res = df[df["experiment"] == "resolution"]
    dfit = pd.read_csv(out / "grids_dfit.csv") if (out / "grids_dfit.csv").exists() else None
    if not res.empty:
        fig, (ax_t, ax_n) = plt.subplots(1, 2, figsize=(13, 4.8))
        for scene, g in res.groupby("scene"):
            g = g.sort_values("d")
            if "ratio_to_embree_lo" in g:  # the median of the per-round ratios with its 95% interval
                r = g["ratio_to_embree"].to_numpy(float)
                low, high = g["ratio_to_embree_lo"].to_numpy(float), g["ratio_to_embree_hi"].to_numpy(float)
                line = ax_t.errorbar(g["d"], r, yerr=[np.maximum(r - low, 0), np.maximum(high - r, 0)],
                                     marker="o", linestyle="none", capsize=2, label=f"{scene} (median, 95% interval)").lines[0]
            elif "ns_per_ray_lo" in g:  # older data: the interval of ns/ray over Embree's median
                r = g["ratio_to_embree"].to_numpy(float)
                e = g["embree_ns_per_ray"].to_numpy(float)
                line = ax_t.errorbar(g["d"], r, yerr=[np.maximum(r - g["ns_per_ray_lo"].to_numpy(float) / e, 0),
                                                      np.maximum(g["ns_per_ray_hi"].to_numpy(float) / e - r, 0)],
                                     marker="o", linestyle="none", capsize=2, label=f"{scene} (median, 95% interval)").lines[0]
            else:
                line, = ax_t.plot(g["d"], g["ratio_to_embree"], marker="o", linestyle="none", label=scene)
            f = None if dfit is None else dfit[dfit["scene"] == scene]
            if f is not None and not f.empty:
                f = f.iloc[0]
                d = np.geomspace(g["d"].min(), g["d"].max(), 60)
                model = (f["c0"] + f["c1"] * d + f["c2"] / d ** 2) / g["embree_ns_per_ray"].iloc[0]
                ax_t.plot(d, model, color=line.get_color(), linewidth=1,
                          label=(f"{scene}: fit c0 + c1·d + c2/d², d* = {f['d_star']:.2f} [{f['d_star_lo']:.2f}, "
                                 f"{f['d_star_hi']:.2f}]" if "d_star_lo" in f else
                                 f"{scene}: fit c0 + c1·d + c2/d², d* = {f['d_star']:.2f} ± {f['d_star_se']:.2f}"))
            ax_n.plot(g["d"], g["prim_tests_per_ray"], marker="o", color=line.get_color(), label=f"{scene}: tests")
            ax_n.plot(g["d"], g["cells_per_ray"], marker="x", linestyle="--", color=line.get_color(),
                      label=f"{scene}: cells")
        for ax in (ax_t, ax_n):
            ax.axvline(3.0, color="grey", linewidth=0.8, linestyle=":")
            ax.set_xscale("log", base=2)
            ax.set_yscale("log")
            ax.set_xlabel("density d (max(nx,ny,nz) = d·∛n)")
            ax.grid(True, which="both", alpha=0.3)
        ax_t.set_ylabel("uniform grid time / Embree time (1 thread)")
        ax_t.set_title("Time per ray relative to Embree; dotted: the lecture's d = 3")
        ax_n.set_ylabel("primitive tests or cells per ray")
        ax_n.set_title("Primitive tests and cells visited per ray")
        legend_outside(ax_t, fontsize=7)
        legend_outside(ax_n, fontsize=7)
        fig.tight_layout()
        fig.savefig(out / "grids_resolution.png", dpi=120)
        plt.close(fig)

    cmp = df[df["experiment"] == "compare"]
    if not cmp.empty:
        scenes = list(dict.fromkeys(cmp["scene"]))
        accels = list(dict.fromkeys(cmp["accel"]))
        fig, ax = plt.subplots(figsize=(8, 4.5))
        width = 0.8 / len(accels)
        x = np.arange(len(scenes))
        for i, a in enumerate(accels):
            vals = [cmp[(cmp["scene"] == s) & (cmp["accel"] == a)]["ratio_to_embree"].mean() for s in scenes]
            ax.bar(x + i * width, vals, width, label=a)
        ax.axhline(1.0, color="black", linewidth=0.8)
        ax.set_xticks(x + width * (len(accels) - 1) / 2)
        ax.set_xticklabels(scenes)
        ax.set_yscale("log")
        ax.set_ylabel("time per ray / Embree (1 thread)")
        ax.set_title("Where grids work (grass) and where they fail (sphereflake, stadium)")
        ax.grid(True, axis="y", which="both", alpha=0.3)
        legend_outside(ax, fontsize=8)
        fig.tight_layout()
        fig.savefig(out / "grids_compare.png", dpi=120)
        plt.close(fig)

    teapot = out / "grids_teapot.csv"
    if teapot.exists():
        t = pd.read_csv(teapot)
        fits = read_fits(out / "grids_fits.csv")
        fig, (ax, bx) = plt.subplots(1, 2, figsize=(13, 4.8))
        cmap = plt.get_cmap("tab10")
        for i, (accel, g) in enumerate(t.groupby("accel", sort=False)):
            g = g.sort_values("ratio")
            if accel != "embree":
                ax.plot(g["ratio"], g["ops_per_ray"], marker="o", linestyle="none", color=cmap(i), label=accel)
                row = fit_row(fits, accel, "ops_per_ray", "power")
                if row is not None:
                    draw_fit(ax, row, cmap(i), "-", f"{accel}: fit c·R^α, α = {row['b']:.2f} ± {row['b_se']:.2f}")
            bx.plot(g["ratio"], g["ns_per_ray"] / g["embree_ns_per_ray"], marker="o", color=cmap(i), label=accel)
        for a in (ax, bx):
            a.set_xscale("log", base=2)
            a.set_yscale("log")
            a.set_xlabel("stadium size R (field length / object diagonal)")
            a.grid(True, which="both", alpha=0.3)
            legend_outside(a, fontsize=7)
        ax.set_ylabel("operations per ray aimed at the object")
        ax.set_title("The teapot in a stadium: work per ray at the teapot", fontsize=9)
        bx.set_ylabel("time per ray / Embree's (1 thread)")
        bx.set_title("time relative to Embree on the same rays", fontsize=9)
        fig.tight_layout()
        fig.savefig(out / "grids_teapot.png", dpi=110)
        plt.close(fig)
