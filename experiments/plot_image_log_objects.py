"""Plot of exp_image_log_objects: per-ray time against triangle count, brute force and Embree,
with the fits a + b·N and a + b·log2 N."""
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402


def plot(out: pathlib.Path) -> None:
    csv = out / "image_log_objects.csv"
    if not csv.exists():
        return
    df = pd.read_csv(csv)
    fig, ax = plt.subplots(figsize=(7.5, 5))
    markers = {"brute": "o", "embree": "s"}
    for (family, accel), g in df.groupby(["family", "accel"]):
        g = g.sort_values("triangles")
        n = g["triangles"].to_numpy(float)
        y = g["ns_per_ray"].to_numpy(float)
        line, = ax.plot(n, y, marker=markers.get(accel, "x"), linestyle="none", label=f"{accel}, {family}")
        if accel == "brute":
            alpha, log_c = np.polyfit(np.log(n), np.log(y), 1)
            xs = np.geomspace(n.min(), n.max(), 50)
            ax.plot(xs, np.exp(log_c) * xs ** alpha, color=line.get_color(), linewidth=1,
                    label=f"fit {np.exp(log_c):.2f}·N^{alpha:.2f}")
        else:
            b, a = np.polyfit(np.log2(n), y, 1)
            xs = np.geomspace(n.min(), n.max(), 50)
            ax.plot(xs, a + b * np.log2(xs), color=line.get_color(), linewidth=1,
                    label=f"fit {a:.0f} + {b:.1f}·log2 N")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("triangles N")
    ax.set_ylabel("ns per ray (1 thread)")
    ax.set_title("Brute force grows like N, Embree like log N")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "image_log_objects.png", dpi=120)
    plt.close(fig)
