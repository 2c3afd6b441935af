#!/usr/bin/python3
"""The report's figures keep at most 12 entries in each legend (issue 30): make_report.py's
draw_figures (every experiments/plot_*.py) draws into a copy of a results directory while
Figure.savefig notes the entries of each legend on the figure it saves (the figure's own and its
axes').

    tests/check_figure_legends.py docs/results

prints one line per figure over the limit and exits 1 if there is one, 2 on unusable input."""
import pathlib
import shutil
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.figure  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "experiments"))
import make_report  # noqa: E402

MAX_ENTRIES = 12


def legend_sizes(fig):
    """The entry count of each legend on `fig`."""
    legends = list(fig.legends) + [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    return [len(legend.get_texts()) for legend in legends]


def draw_all(results_dir):
    """{figure file name: its largest legend's entry count (0 without one)} for every figure the
    plot scripts save, drawn into a temporary copy of `results_dir`."""
    drawn = {}
    save = matplotlib.figure.Figure.savefig

    def counting_save(fig, fname, *args, **kwargs):
        drawn[pathlib.Path(str(fname)).name] = max(legend_sizes(fig), default=0)
        return save(fig, fname, *args, **kwargs)

    with tempfile.TemporaryDirectory() as tmp:
        copy = pathlib.Path(tmp) / "results"
        shutil.copytree(results_dir, copy)
        matplotlib.figure.Figure.savefig = counting_save
        try:
            make_report.draw_figures(copy)
        finally:
            matplotlib.figure.Figure.savefig = save
    return drawn


def faults(drawn):
    return [f"{name}: a legend of {n} entries (at most {MAX_ENTRIES})" for name, n in sorted(drawn.items())
            if n > MAX_ENTRIES]


def main():
    if len(sys.argv) != 2 or not pathlib.Path(sys.argv[1]).is_dir():
        print("check_figure_legends.py: error: give one results directory", file=sys.stderr)
        return 2
    found = faults(draw_all(sys.argv[1]))
    for line in found:
        print(line)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
