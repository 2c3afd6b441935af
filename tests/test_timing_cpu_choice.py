#!/usr/bin/python3
"""experiments/timing_cpu.py and its use by make_report.py: of the noise floor traced pinned to each
CPU, the CPU where our `bvh` was fastest is chosen, written to timing_cpu.json and named in the
report's header and results.json; a probe directory that cannot be read is one error line and exit
status 2."""
import json
import pathlib
import subprocess
import sys
import tempfile
import unittest

EXPERIMENTS = pathlib.Path(__file__).resolve().parent.parent / "experiments"
sys.path.insert(0, str(EXPERIMENTS))
import timing_cpu  # noqa: E402


def write_probe(directory: pathlib.Path, cpu: int, ns: float, embree_ns: float, name=None):
    d = directory / (name or f"cpu-{cpu}")
    d.mkdir(parents=True, exist_ok=True)
    ratio = embree_ns / ns if ns else 0.0
    (d / "noise_floor.json").write_text(json.dumps({
        "median_ns": ns, "median_ns_ci95": [ns * 0.98, ns * 1.01], "embree_median_ns": embree_ns,
        "ratio": ratio, "ci95": [ratio * 0.99, ratio * 1.01], "replicates": 20}))


class Choose(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.addCleanup(self.dir.cleanup)
        self.out = pathlib.Path(self.dir.name)

    def run_script(self):
        return subprocess.run([sys.executable, str(EXPERIMENTS / "timing_cpu.py"), str(self.out)], capture_output=True,
                              text=True, timeout=60)

    def test_the_cpu_where_ours_is_fastest_is_chosen(self):
        # CPU 0 has the better ratio to Embree, CPU 1 the faster `bvh`: the rule is ours' time.
        write_probe(self.out, 0, 284.0, 215.0)
        write_probe(self.out, 1, 236.0, 170.0)
        write_probe(self.out, 10, 250.0, 190.0)
        r = self.run_script()
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(r.stdout.strip(), "1")
        summary = json.loads((self.out / "timing_cpu.json").read_text())
        self.assertEqual(summary["chosen"], 1)
        self.assertEqual([row["cpu"] for row in summary["cpus"]], [0, 1, 10])
        line = timing_cpu.header_line(summary)
        self.assertIn("CPU 1, pinned", line)
        self.assertIn("CPU 0: `bvh` 284 ns/ray", line)
        self.assertIn("the slowest CPU took 1.20× the fastest's time", line)

    def test_one_cpu(self):
        write_probe(self.out, 3, 240.0, 190.0)
        self.assertEqual(self.run_script().stdout.strip(), "3")
        self.assertIn("one CPU only", timing_cpu.header_line(json.loads((self.out / "timing_cpu.json").read_text())))

    def test_unreadable_probes_are_one_error_line(self):
        cases = {
            "empty": lambda: None,
            "not json": lambda: (self.out / "cpu-0").mkdir() or (self.out / "cpu-0" / "noise_floor.json").write_text("{"),
            "missing key": lambda: (self.out / "cpu-0").mkdir() or (self.out / "cpu-0" / "noise_floor.json").write_text(
                json.dumps({"median_ns": 1.0})),
            "zero time": lambda: write_probe(self.out, 0, 0.0, 1.0),
            "bad name": lambda: write_probe(self.out, 0, 200.0, 150.0, name="cpu-x"),
        }
        for name, make in cases.items():
            with self.subTest(name), tempfile.TemporaryDirectory() as d:
                self.out = pathlib.Path(d)
                make()
                r = self.run_script()
                self.assertEqual(r.returncode, 2, name)
                self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
                self.assertTrue(r.stderr.startswith("timing_cpu.py: error: "), r.stderr)
                self.assertFalse((self.out / "timing_cpu.json").exists())

    def test_header_line_without_a_summary_is_empty(self):
        self.assertEqual(timing_cpu.header_line(None), "")
        self.assertEqual(timing_cpu.header_line({"chosen": 0}), "")

    def test_make_report_names_the_cpu_in_the_header_and_results_json(self):
        write_probe(self.out / "timing_cpu", 0, 284.0, 203.0)
        write_probe(self.out / "timing_cpu", 1, 236.0, 189.0)
        self.assertEqual(subprocess.run([sys.executable, str(EXPERIMENTS / "timing_cpu.py"),
                                         str(self.out / "timing_cpu")], capture_output=True).returncode, 0)
        (self.out / "spatial.md").write_text("## Spatial\n\nMeasured by exp_spatial.\n")
        r = subprocess.run([sys.executable, str(EXPERIMENTS / "make_report.py"), str(self.out)], capture_output=True,
                           text=True, timeout=300)
        self.assertEqual(r.returncode, 0, r.stderr)
        page = (self.out / "README.md").read_text()
        self.assertIn("**Where single-thread timings ran**: CPU 1", page)
        self.assertLess(page.index("Where single-thread timings ran"), page.index("## Spatial"))
        self.assertEqual(json.loads((self.out / "results.json").read_text())["timing_cpu"]["chosen"], 1)


if __name__ == "__main__":
    unittest.main()
