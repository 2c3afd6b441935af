#!/usr/bin/python3
"""tests/check_figure_legends.py: it counts the entries of a figure's legends and flags one over 12,
and every figure the committed docs/results/ draws keeps within the limit."""
import pathlib
import sys
import unittest

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))
import check_figure_legends  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402  (Agg, set by check_figure_legends)


class FigureLegends(unittest.TestCase):
    def test_counts_the_figure_legend_and_each_axes_legend(self):
        fig, (left, right) = plt.subplots(1, 2)
        for i in range(13):
            left.plot([0, 1], [i, i], label=f"line {i}")
        left.legend()
        right.plot([0, 1], [0, 1], label="one")
        right.legend()
        fig.legend(handles=left.get_lines()[:3])
        self.assertEqual(sorted(check_figure_legends.legend_sizes(fig)), [1, 3, 13])
        plt.close(fig)

    def test_flags_a_legend_over_twelve(self):
        found = check_figure_legends.faults({"a.png": 13, "b.png": 12, "c.png": 0})
        self.assertEqual(len(found), 1)
        self.assertIn("a.png", found[0])

    def test_the_committed_figures_keep_within_twelve(self):
        drawn = check_figure_legends.draw_all(ROOT / "docs" / "results")
        self.assertGreaterEqual(len(drawn), 10, drawn)  # the check drew the report's figures, not none
        self.assertEqual(check_figure_legends.faults(drawn), [])


if __name__ == "__main__":
    unittest.main()
