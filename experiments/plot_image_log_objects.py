"""Plots of exp_image_log_objects: operations and time per ray against N for every structure (claim 1),
the families where log N fails, and query cost against memory (claim 5). Fitted curves come from
image_log_objects_fits.csv."""
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from figures import draw_fit, fit_row, legend_outside, read_fits  # noqa: E402

BENIGN = ["soup", "bunny", "sphereflake"]
FAILING = ["dust", "needles", "fan", "row"]
TITLES = {"soup": "random triangles (soup)", "bunny": "the bunny, decimated / subdivided",
          "sphereflake": "sphereflake (spheres)", "dust": "dust: rays escape", "needles": "needles: boxes overlap",
          "fan": "fan: a vertex of valence N", "row": "row: near misses along the ray"}


def _colors(accels):
    cmap = plt.get_cmap("tab10")
    return {a: cmap(i % 10) for i, a in enumerate(accels)}


def _panel(ax, df, fits, family, quantity, colors, fit_model):
    g = df[df["family"] == family]
    for accel, h in g.groupby("accel", sort=False):
        h = h.sort_values("primitives")
        y = h[quantity].to_numpy(float)
        if not (y > 0).any():
            continue
        ax.plot(h["primitives"], y, marker="o", markersize=3, linestyle="none", color=colors[accel], label=accel)
        model = fit_model
        if accel == "brute":
            model = "linear" if quantity == "ns_per_ray" else "power"
        draw_fit(ax, fit_row(fits, f"{family}|{accel}", quantity, model), colors[accel])
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("primitives N")
    ax.grid(True, which="both", alpha=0.3)


def plot(out: pathlib.Path) -> None:
    csv = out / "image_log_objects.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)
    fits = read_fits(out / "image_log_objects_fits.csv")
    colors = _colors(list(dict.fromkeys(df["accel"])))

    fams = [f for f in BENIGN if f in set(df["family"])]
    if fams:
        fig, axes = plt.subplots(2, len(fams), figsize=(5.2 * len(fams), 9), squeeze=False)
        for j, fam in enumerate(fams):
            _panel(axes[0][j], df, fits, fam, "ops_per_ray", colors, "log")
            axes[0][j].set_ylabel("operations per ray (node + leaf visits + tests)")
            axes[0][j].set_title(f"{TITLES[fam]}: operations\n(lines: fits a + b·log2 N; brute: c·N^α)", fontsize=9)
            _panel(axes[1][j], df, fits, fam, "ns_per_ray", colors, "power")
            axes[1][j].set_ylabel("ns per ray (1 thread)")
            axes[1][j].set_title(f"{TITLES[fam]}: time\n(lines: fits c·N^α; brute: a + b·N)", fontsize=9)
        handles = {}
        for ax in axes.flat:
            for h, l in zip(*ax.get_legend_handles_labels()):
                handles.setdefault(l, h)
        fig.legend(handles.values(), handles.keys(), loc="lower center", ncol=len(handles), fontsize=8,
                   title="structure (as `raylab accels` names it)", title_fontsize=8)
        fig.tight_layout(rect=(0, 0.06, 1, 1))
        fig.savefig(out / "image_log_objects.png", dpi=110)
        plt.close(fig)

    fams = [f for f in FAILING if f in set(df["family"])]
    if fams:
        fig, axes = plt.subplots(1, len(fams), figsize=(4.3 * len(fams), 4.6), squeeze=False)
        for j, fam in enumerate(fams):
            ax = axes[0][j]
            _panel(ax, df, fits, fam, "ops_per_ray", colors, "power")
            ax.set_ylabel("operations per ray")
            ax.set_title(f"{TITLES[fam]}\n(lines: fits c·N^α)", fontsize=9)
        handles = {}
        for ax in axes.flat:
            for h, l in zip(*ax.get_legend_handles_labels()):
                handles.setdefault(l, h)
        fig.legend(handles.values(), handles.keys(), loc="lower center", ncol=len(handles), fontsize=8)
        fig.tight_layout(rect=(0, 0.08, 1, 1))
        fig.savefig(out / "image_log_objects_failures.png", dpi=110)
        plt.close(fig)

    # Claim 5: query operations against memory, every structure with a byte count.
    # Embree reports no operations (its memory is in the section's table). Colour: the structure;
    # marker: the scene family; the bounds are named on their curves, not in the legends.
    mem = df[(df["bytes"] > 0) & ~df["accel"].isin(["brute", "embree"]) & (df["family"] != "dust")]
    mem = mem[mem["ops_per_ray"] > 0]
    if not mem.empty:
        from matplotlib.lines import Line2D
        fig, ax = plt.subplots(figsize=(11, 6.5))
        markers = {"soup": "o", "bunny": "D", "sphereflake": "s", "needles": "^", "fan": "v", "row": "x"}
        for (fam, accel), g in mem.groupby(["family", "accel"], sort=False):
            g = g.sort_values("primitives")
            ax.plot(g["bytes"], g["ops_per_ray"], marker=markers.get(fam, "."), markersize=4, color=colors[accel],
                    linewidth=0.8)
        x_lo, x_hi = mem["bytes"].min() / 3, mem["bytes"].max() * 3
        y_lo, y_hi = mem["ops_per_ray"].min() / 3, mem["ops_per_ray"].max() * 3
        # Each bound's trade-off with unit constants: memory n^k bytes buys a query cost f(n), drawn
        # over the measured memory (n = memory^(1/k)).
        m = np.geomspace(x_lo, x_hi, 60)
        for k, query, label, style, at, dy in (
                (5, lambda n: np.log2(n), "Pellegrini 1993: n^5 space, log n query", "--", 0.85, 5),
                (3, lambda n: np.full_like(n, 4.0), "Mohaban-Sharir 1997 (spheres): n^3, n^ε", ":", 0.2, -11),
                (2, lambda n: np.log2(n) ** 2, "Aronov-de Berg-Gray 2008 (fat): n^2, log² n", "-.", 0.75, 5),
                (1, lambda n: n / 16, "brute force: 16 bytes·n, n tests", "-", 0.5, 5)):
            n = m ** (1.0 / k) if k > 1 else m
            q = query(n)
            keep = (q > y_lo) & (q < y_hi)
            if not keep.any():
                continue
            ax.plot(m[keep], q[keep], color="black" if k > 1 else "grey", linestyle=style, linewidth=1)
            i = np.flatnonzero(keep)[int(len(np.flatnonzero(keep)) * at)]
            ax.annotate(label, (m[i], q[i]), xytext=(0, dy), textcoords="offset points", fontsize=8,
                        color="black" if k > 1 else "0.35", ha="center")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(x_lo, x_hi)
        ax.set_ylim(y_lo, y_hi)
        ax.set_xlabel("memory of the structure (bytes); the bounds drawn with unit constants, n = memory^(1/k)")
        ax.set_ylabel("query cost: operations per ray")
        ax.set_title("Query cost against memory as n grows (each line: one structure on one family, n rising)",
                     fontsize=10)
        ax.grid(True, which="major", alpha=0.3)
        structures = [a for a in dict.fromkeys(mem["accel"])]
        leg = ax.legend(handles=[Line2D([], [], color=colors[a], marker="o", label=a) for a in structures],
                        title="colour: structure", fontsize=8, title_fontsize=8, loc="upper left",
                        bbox_to_anchor=(1.01, 1.0))
        ax.add_artist(leg)
        fams = [f for f in dict.fromkeys(mem["family"])]
        ax.legend(handles=[Line2D([], [], color="0.3", marker=markers.get(f, "."), linestyle="none", label=f)
                           for f in fams], title="marker: scene family", fontsize=8, title_fontsize=8,
                  loc="lower left", bbox_to_anchor=(1.01, 0.0))
        fig.tight_layout()
        fig.savefig(out / "ray_shooting_bounds.png", dpi=100)
        plt.close(fig)
