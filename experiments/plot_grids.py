"""Plots of exp_grids: time and primitive tests per ray against the grid density d (with Embree's
time for reference), and uniform/nested/two-level grids against Embree on each scene."""
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402


def plot(out: pathlib.Path) -> None:
    csv = out / "grids.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)

    res = df[df["experiment"] == "resolution"]
    if not res.empty:
        fig, (ax_t, ax_n) = plt.subplots(1, 2, figsize=(11, 4.5))
        for scene, g in res.groupby("scene"):
            g = g.sort_values("d")
            line, = ax_t.plot(g["d"], g["ratio_to_embree"], marker="o", label=scene)
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
        ax_n.set_ylabel("per ray")
        ax_n.set_title("Primitive tests and cells visited per ray")
        ax_t.legend(fontsize=8)
        ax_n.legend(fontsize=7)
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
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(out / "grids_compare.png", dpi=120)
        plt.close(fig)
