#!/usr/bin/python3
"""tests/check_timing_intervals.py: it flags a timing column without its interval and a file
without a replicate count, accepts each form of interval the report writes, and finds no fault in
the committed docs/results/."""
import pathlib
import sys
import tempfile
import unittest

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))
import check_timing_intervals  # noqa: E402


class TimingIntervals(unittest.TestCase):
    def faults(self, header, name="x.csv"):
        with tempfile.TemporaryDirectory() as d:
            path = pathlib.Path(d) / name
            path.write_text(",".join(header) + "\n1" + ",1" * (len(header) - 1) + "\n")
            return check_timing_intervals.faults_of(path)

    def test_a_timing_without_its_interval(self):
        f = self.faults(["accel", "ns_per_ray", "embree_ns_per_ray", "ns_per_ray_lo", "ns_per_ray_hi", "rounds"])
        self.assertEqual(len(f), 1)
        self.assertIn("embree_ns_per_ray:", f[0])
        f = self.faults(["scene", "build_s", "choose_s", "build_lo_s", "build_hi_s", "rounds"])
        self.assertEqual(len(f), 1)
        self.assertIn("choose_s:", f[0])

    def test_no_replicate_count(self):
        f = self.faults(["accel", "ns_per_ray", "ns_per_ray_lo", "ns_per_ray_hi"])
        self.assertEqual(len(f), 1)
        self.assertIn("no replicate count", f[0])
        self.assertEqual(self.faults(["accel", "nodes_per_ray", "bytes"]), [])  # no timing, no count needed

    def test_every_form_the_report_writes(self):
        self.assertEqual(self.faults(["ns_per_ray", "ns_per_ray_lo", "ns_per_ray_hi", "replicates"]), [])
        self.assertEqual(self.faults(["auto_total_s", "auto_total_lo_s", "auto_total_hi_s", "rounds"]), [])
        self.assertEqual(self.faults(["build_s", "build_s_lo", "build_s_hi", "rounds"]), [])
        self.assertEqual(self.faults(["passes", "ns_per_ray_min", "ns_per_ray_median", "ns_per_ray_max", "build_s",
                                      "build_s_max", "embree_ns_per_ray_min", "embree_ns_per_ray_max"]), [])
        # A fastest pass with its slowest in X_hi only where the file is known to write it so.
        header = ["measured_ns_per_visit", "measured_ns_per_visit_hi", "counters_ns_per_visit", "passes"]
        self.assertEqual(self.faults(header, "cost_memory.csv"), [])
        self.assertEqual(len(self.faults(header, "other.csv")), 2)  # the prediction is exempt in cost_memory only

    def test_the_committed_report(self):
        results = ROOT / "docs" / "results"
        self.assertTrue(list(results.glob("*.csv")))
        faults = []
        for path in sorted(results.glob("*.csv")):
            faults += check_timing_intervals.faults_of(path)
        self.assertEqual(faults, [])


if __name__ == "__main__":
    unittest.main()
