#!/usr/bin/python3
"""The report's Markdown and results.json: tests/check_markdown_tables.py flags the faults that
keep a table from rendering; make_report.py, run on a small results directory, writes
results.json in the format compare_results.py reads, names the machine, links each summary row to
its verdict paragraph, orders sections by claim, and lists the changes against an earlier
results.json with their cause; every table it writes parses."""
import csv
import json
import pathlib
import subprocess
import sys
import tempfile
import unittest

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "experiments"))
import check_markdown_tables  # noqa: E402
import compare_results  # noqa: E402

COLUMNS = ["claim", "title", "verdict", "key", "anchor", "key_name", "key_value", "ci95_lo", "ci95_hi", "replicates",
           "spec", "interval", "threshold", "threshold_direction", "threshold_value", "threshold_tolerance", "command"]


class TableChecker(unittest.TestCase):
    def faults(self, text):
        return check_markdown_tables.table_faults(text.splitlines())

    def test_good_table(self):
        self.assertEqual(self.faults("x\n\n| a | b \\| c |\n|---|:---:|\n| 1 | 2 |\n| `x\\|y` | |\n"), [])

    def test_rows_joined_by_double_pipe(self):
        f = self.faults("| a | b |\n|---|---|\n| 1 | 2 || 3 | 4 |\n")
        self.assertEqual(len(f), 1)
        self.assertIn("'||'", f[0])

    def test_missing_separator_and_ragged_row(self):
        self.assertIn("separator", self.faults("| a | b |\n| 1 | 2 |\n")[0])
        f = self.faults("| a | b |\n|---|---|\n| 1 | 2 | 3 |\n")
        self.assertEqual(len(f), 1)
        self.assertIn("3 columns, the header has 2", f[0])

    def test_code_blocks_are_not_tables(self):
        self.assertEqual(self.faults("```\n| not | a table\n```\n"), [])

    def test_hand_written_docs(self):
        files = check_markdown_tables.markdown_files([ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))])
        self.assertTrue(files)
        for f in files:
            self.assertEqual(check_markdown_tables.table_faults(f.read_text().splitlines(), str(f)), [])


def verdict_row(claim, verdict, value, lo, hi, spec, anchor):
    return {"claim": claim, "title": f"claim {claim} | in words", "verdict": verdict, "key": f"x = {value}",
            "anchor": anchor, "key_name": f"x of {claim}", "key_value": value, "ci95_lo": lo, "ci95_hi": hi,
            "replicates": 6, "spec": spec, "interval": "± t(0.975, 4)·s.e.", "threshold": "x below 0.25",
            "threshold_direction": "below", "threshold_value": 0.25, "threshold_tolerance": "nan",
            "command": "build/experiments/exp_x --mode quick"}


def noise_floor(ratio, lo, hi, ns=234.0, embree_ns=188.0):
    return {"ratio": ratio, "ci95": [lo, hi], "median_ns": ns, "embree_median_ns": embree_ns, "replicates": 20}


class NoiseFloorDrift(unittest.TestCase):
    """The noise floor at the end of a run against the one at its start (make_report.noise_floor_drift_line)."""

    @classmethod
    def setUpClass(cls):
        import make_report
        cls.line = staticmethod(make_report.noise_floor_drift_line)

    def test_overlapping_intervals_held(self):
        line = self.line(noise_floor(0.80, 0.79, 0.81), noise_floor(0.805, 0.80, 0.82))
        self.assertIn("0.800 [0.790, 0.810]", line)
        self.assertIn("speed held", line)
        self.assertNotIn("changed during the run", line)
        self.assertNotIn("drifted by", line)

    def test_disjoint_intervals_changed(self):
        line = self.line(noise_floor(0.713, 0.708, 0.718, 309.5, 220.3), noise_floor(0.80, 0.79, 0.81))
        self.assertIn("changed during the run** (12.2%)", line)
        self.assertIn("(310 and 220 ns/ray)", line)

    def test_disjoint_intervals_within_the_threshold_drifted(self):
        # 1.5%: the intervals of 20 rounds are narrow enough to separate it, yet it is no change of state.
        line = self.line(noise_floor(0.800, 0.798, 0.802), noise_floor(0.812, 0.810, 0.814))
        self.assertIn("drifted by 1.5%", line)
        self.assertNotIn("changed during the run", line)
        self.assertIn("rule, stated before the figures", line)
        # Just beyond the threshold it is a change.
        beyond = self.line(noise_floor(0.800, 0.798, 0.802), noise_floor(0.8416, 0.840, 0.843))
        self.assertIn("changed during the run** (5.2%)", beyond)

    def test_missing_or_malformed_says_nothing(self):
        self.assertEqual(self.line(None, noise_floor(0.8, 0.79, 0.81)), "")
        self.assertEqual(self.line(noise_floor(0.8, 0.79, 0.81), {"ratio": 0.8}), "")
        self.assertEqual(self.line({"spec": "old file"}, noise_floor(0.8, 0.79, 0.81)), "")


class DefaultKernelLine(unittest.TestCase):
    """The header's cost of the certified default: goals decided by each row's interval, not its point."""

    @classmethod
    def setUpClass(cls):
        import make_report
        cls.make_report = make_report

    def write(self, name, columns, rows):
        path = pathlib.Path(self.dir.name) / name
        with path.open("w", newline="") as f:
            w = csv.writer(f)
            w.writerow(columns)
            w.writerows(rows)
        return path

    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.addCleanup(self.dir.cleanup)

    def test_rows_are_met_missed_or_straddling_by_their_interval(self):
        path = self.write("certainty_structures.csv", ["structure", "ratio_median", "ratio_lo", "ratio_hi"],
                          [["bvh", 1.05, 1.02, 1.08], ["bsp", 1.09, 1.05, 1.17], ["kdtree", 1.14, 1.12, 1.16],
                           ["grid", 0.6, 0.55, 0.7]])
        line = self.make_report.certified_cost_sentence(path)
        self.assertIn("0.60–1.14×", line)
        self.assertIn("2 of 4 rows met it, 1 missed it and 1 straddle it", line)
        self.assertIn("1.140 [1.120, 1.160]", line)

    def test_bvh_against_embree_with_intervals(self):
        columns = ["scene", "rays", "accel", "ratio_to_embree", "ratio_to_embree_lo", "ratio_to_embree_hi",
                   "ratio_to_embree_robust", "ratio_to_embree_robust_lo", "ratio_to_embree_robust_hi"]
        path = self.write("certainty.csv", columns, [
            ["s", "primary", "bvh", 0.93, 0.9, 0.95, 1.01, 0.99, 1.03],
            ["s", "diffuse", "bvh", 0.80, 0.78, 0.82, 0.93, 0.9, 0.95],
            ["s", "diffuse", "embree", 1.0, 1.0, 1.0, 1.2, 1.1, 1.3],
            ["s", "vertices", "bvh", 0.1, 0.1, 0.1, 0.1, 0.1, 0.1]])
        line = self.make_report.default_bvh_against_embree_sentence(path)
        self.assertIn("0.80 [0.78, 0.82] to 0.93 [0.90, 0.95] of Embree's throughput", line)
        self.assertIn("0.93 [0.90, 0.95] to 1.01 [0.99, 1.03] of Embree robust's", line)
        self.assertIn("of 2 scene and ray kind rows", line)

    def test_files_without_intervals_or_missing_say_nothing(self):
        old = self.write("old.csv", ["scene", "rays", "accel", "ns_per_ray"], [["s", "primary", "bvh", 100]])
        self.assertEqual(self.make_report.certified_cost_sentence(old), "")
        self.assertEqual(self.make_report.default_bvh_against_embree_sentence(old), "")
        missing = pathlib.Path(self.dir.name) / "none.csv"
        self.assertEqual(self.make_report.certified_cost_sentence(missing), "")
        bad = self.write("bad.csv", ["ratio_median", "ratio_lo", "ratio_hi"], [["x", 1, 2]])
        self.assertEqual(self.make_report.certified_cost_sentence(bad), "")


class MakeReport(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        self = cls
        self.tmp = tempfile.TemporaryDirectory()
        out = self.out = pathlib.Path(self.tmp.name) / "results"
        out.mkdir()
        with (out / "crofton.verdicts.csv").open("w", newline="") as f:
            w = csv.DictWriter(f, COLUMNS)
            w.writeheader()
            w.writerow(verdict_row("3", "confirmed", 0.1, 0.05, 0.15, "exp_crofton:directions=2000", "claim-3"))
            w.writerow(verdict_row("3c", "holds only under stated conditions", 0.2, 0.1, 0.3, "bvh:width=2", "claim-3"))
        with (out / "image_log_objects.verdicts.csv").open("w", newline="") as f:
            w = csv.DictWriter(f, COLUMNS[:5])  # the old five columns: still read
            w.writeheader()
            w.writerow({"claim": "1", "title": "log N", "verdict": "refuted", "key": "α = 0.3", "anchor": "claim-1"})
        (out / "crofton.md").write_text('<a id="claim-3"></a>\n\n## Crofton\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\n'
                                        '<a id="verdict-3"></a>**Verdict (claim 3): confirmed.**\n')
        (out / "image_log_objects.md").write_text('<a id="claim-1"></a>\n\n## Image log objects\n')
        (out / "noise_floor.md").write_text("## Noise floor\n")
        (out / "noise_floor.json").write_text(json.dumps({"spec": "bvh vs embree", "replicates": 20, "cv": 0.04}))
        (out / "noise_floor_end").mkdir()
        (out / "noise_floor_end" / "noise_floor.json").write_text(json.dumps(noise_floor(0.71, 0.70, 0.72)))
        previous = compare_results.parse_results(json.dumps({
            "format": "raylab-results", "version": 1, "revision": self.head(), "machine": {}, "noise_floor": None,
            "claims": [{"id": "3", "verdict": "confirmed", "key": {"name": "x of 3", "value": 0.3, "ci95": [0.25, 0.35],
                                                                   "replicates": 6, "spec": "exp_crofton:directions=2000"}},
                       {"id": "3c", "verdict": "refuted", "key": {"name": "x of 3c", "value": 0.2, "ci95": [0.1, 0.3],
                                                                  "replicates": 6, "spec": "bvh:width=4"}}],
            "numbers": []}), "previous")
        (pathlib.Path(self.tmp.name) / "previous.json").write_text(json.dumps(previous))
        r = subprocess.run([sys.executable, str(ROOT / "experiments" / "make_report.py"), str(out), "--previous",
                            str(pathlib.Path(self.tmp.name) / "previous.json")],
                           capture_output=True, text=True, cwd=ROOT, timeout=300)
        if r.returncode != 0:
            raise AssertionError(f"make_report.py failed: {r.stderr}")
        self.page = (out / "README.md").read_text()
        self.results = json.loads((out / "results.json").read_text())

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    @staticmethod
    def head():
        return subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True, cwd=ROOT).stdout.strip()

    def test_results_json(self):
        self.assertEqual(self.results["noise_floor_end"]["ratio"], 0.71)
        r = compare_results.parse_results(json.dumps(self.results), "results.json")
        self.assertEqual([c["id"] for c in r["claims"]], ["1", "3", "3c"])
        by_id = {c["id"]: c for c in r["claims"]}
        self.assertEqual(by_id["3c"]["verdict"], "conditional")
        self.assertEqual(by_id["3"]["key"]["ci95"], [0.05, 0.15])
        self.assertEqual(by_id["3"]["key"]["spec"], "exp_crofton:directions=2000")
        self.assertEqual(by_id["3"]["threshold"]["direction"], "below")
        self.assertIsNone(by_id["1"]["key"])
        self.assertEqual(r["noise_floor"]["replicates"], 20)
        self.assertTrue(r["machine"]["cpu"])
        self.assertIn("CGAL", r["machine"]["libraries"])

    def test_page(self):
        self.assertIn("**Machine**", self.page)
        self.assertIn("(#verdict-3)", self.page)  # the fragment has the verdict anchor
        self.assertIn("(#claim-1)", self.page)  # it has none: the section
        order = [self.page.index(h) for h in ["## Noise floor", "## Image log objects", "## Crofton"]]
        self.assertEqual(order, sorted(order))
        self.assertEqual(check_markdown_tables.table_faults(self.page.splitlines(), "README.md"), [])

    def test_changes_section_names_causes(self):
        changes = self.page[self.page.index("## Changes since the last report"):self.page.index("## Noise floor")]
        self.assertIn("| 3 | key number x of 3: 0.3 [0.25, 0.35] → 0.1 | noise", changes)
        self.assertIn("| 3c | verdict refuted → conditional | spec or default changed: `bvh:width=4` → `bvh:width=2`",
                      changes)


if __name__ == "__main__":
    unittest.main()
