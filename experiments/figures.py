"""Shared pieces of the plot modules (plot_*.py): fitted curves drawn from the coefficients the
experiments wrote to their *_fits.csv files (never refitted here), and legends kept off the data."""
import numpy as np
import pandas as pd


def fitted_curve(model: str, a: float, b: float, x):
    """The curve of a fit row of experiment_common.h's FitsCsv: y(x) for the named model."""
    x = np.asarray(x, dtype=float)
    if model == "log":
        return a + b * np.log2(x)
    if model == "power":
        return a * x ** b
    if model == "linear":
        return a + b * x
    if model == "nlogn":
        return a + b * x * np.log2(x)
    if model == "nlog2n":
        return a + b * x * np.log2(x) ** 2
    raise ValueError(f"unknown model {model}")


def read_fits(path):
    """The fits file as a DataFrame, or None when it is absent."""
    return pd.read_csv(path) if path.exists() else None


def fit_row(fits, series: str, quantity: str, model: str):
    if fits is None:
        return None
    rows = fits[(fits["series"] == series) & (fits["quantity"] == quantity) & (fits["model"] == model)]
    return None if rows.empty else rows.iloc[0]


def draw_fit(ax, row, color, style="-", label=None, samples=60):
    """Draws a fit row over its fitted range (log-spaced x)."""
    if row is None:
        return
    xs = np.geomspace(row["x_min"], row["x_max"], samples)
    ax.plot(xs, fitted_curve(row["model"], row["a"], row["b"], xs), color=color, linestyle=style, linewidth=1,
            label=label)


def legend_outside(ax, fontsize=7, ncol=1):
    """A legend to the right of the axes, where it cannot cover data."""
    ax.legend(fontsize=fontsize, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, ncol=ncol)


def legend_below(ax, fontsize=7, ncol=3):
    """A legend under the axes, where it cannot cover data."""
    ax.legend(fontsize=fontsize, loc="upper center", bbox_to_anchor=(0.5, -0.16), borderaxespad=0.0, ncol=ncol)
