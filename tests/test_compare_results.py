#!/usr/bin/python3
"""experiments/compare_results.py, run as a user runs it: it flags a key number that left the
reference's 95% interval and a flipped verdict, names a changed spec, agrees with itself, and
refuses a malformed or foreign file with one error line and exit status 2."""
import json
import pathlib
import subprocess
import sys
import tempfile
import unittest

TOOL = pathlib.Path(__file__).resolve().parent.parent / "experiments" / "compare_results.py"


def results(claims, revision="a" * 40):
    return {"format": "raylab-results", "version": 1, "revision": revision, "machine": {}, "noise_floor": None,
            "claims": claims, "numbers": []}


def claim(cid, verdict, value, lo, hi, spec="kdtree:builder=sah,sweep=events"):
    return {"id": cid, "verdict": verdict, "threshold": {"text": "t", "direction": "below", "value": 0.25},
            "key": {"name": f"key of {cid}", "value": value, "ci95": [lo, hi], "replicates": 7, "spec": spec}}


class CompareResults(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.addCleanup(self.dir.cleanup)

    def write(self, name, data) -> str:
        path = pathlib.Path(self.dir.name) / name
        path.write_text(data if isinstance(data, str) else json.dumps(data))
        return str(path)

    def run_tool(self, *args):
        return subprocess.run([sys.executable, str(TOOL), *args], capture_output=True, text=True, timeout=60)

    def test_identical_files_agree(self):
        a = self.write("a.json", results([claim("1", "conditional", 0.15, 0.11, 0.19), claim("2", "confirmed", 1.0, 0.99, 1.01)]))
        r = self.run_tool(a, a)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("2 of 2 key numbers of B inside A's 95% interval; verdicts identical: yes", r.stdout)
        self.assertNotIn("moved:", r.stdout)

    def test_flags_moved_number_and_flipped_verdict(self):
        a = self.write("a.json", results([claim("4", "confirmed", 0.363, 0.31, 0.41), claim("3c", "confirmed", 0.97, 0.91, 1.03)]))
        b = self.write("b.json", results([claim("4", "confirmed", 0.272, 0.17, 0.37), claim("3c", "refuted", 0.95, 0.93, 0.97)],
                                         revision="b" * 40))
        r = self.run_tool(a, b)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("moved: 4", r.stdout)
        self.assertNotIn("moved: 3c", r.stdout)  # 0.95 lies inside A's [0.91, 1.03]
        self.assertIn("flipped: 3c: confirmed -> refuted", r.stdout)
        self.assertIn("1 of 2 key numbers of B inside A's 95% interval; verdicts identical: no", r.stdout)
        j = json.loads(self.run_tool(a, b, "--json").stdout)
        self.assertEqual([m["id"] for m in j["moved"]], ["4"])
        self.assertEqual([f["id"] for f in j["flipped"]], ["3c"])
        self.assertFalse(j["verdicts_identical"])

    def test_names_changed_spec(self):
        a = self.write("a.json", results([claim("7b", "confirmed", 2.18, 1.9, 2.4, spec="kdtree:clip=none")]))
        b = self.write("b.json", results([claim("7b", "confirmed", 14.3, 10.0, 18.6, spec="kdtree:clip=exact")]))
        r = self.run_tool(a, b)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("spec changed: 7b key of 7b: kdtree:clip=none -> kdtree:clip=exact", r.stdout)
        self.assertIn("moved: 7b", r.stdout)

    def test_missing_claim_is_not_identical(self):
        a = self.write("a.json", results([claim("1", "confirmed", 0.1, 0.0, 0.2), claim("2", "confirmed", 1, 0.9, 1.1)]))
        b = self.write("b.json", results([claim("1", "confirmed", 0.1, 0.0, 0.2)]))
        r = self.run_tool(a, b)
        self.assertIn("only in A: 2", r.stdout)
        self.assertIn("verdicts identical: no", r.stdout)

    def assert_refused(self, r, fragment):
        self.assertEqual(r.returncode, 2)
        self.assertEqual(r.stdout, "")
        lines = r.stderr.splitlines()
        self.assertEqual(len(lines), 1, r.stderr)
        self.assertTrue(lines[0].startswith("compare_results: error: "), lines[0])
        self.assertIn(fragment, lines[0])

    def test_refuses_malformed_file(self):
        good = self.write("a.json", results([claim("1", "confirmed", 0.1, 0.0, 0.2)]))
        self.assert_refused(self.run_tool(good, self.write("bad.json", '{"format": "raylab-results", "claims": [')), "not JSON")
        broken = results([{"id": "1", "verdict": "confirmed", "key": {"value": 1, "ci95": "wide"}}])
        self.assert_refused(self.run_tool(good, self.write("broken.json", broken)), "ci95")
        self.assert_refused(self.run_tool(good, str(pathlib.Path(self.dir.name) / "absent.json")), "cannot read")

    def test_refuses_foreign_file(self):
        good = self.write("a.json", results([claim("1", "confirmed", 0.1, 0.0, 0.2)]))
        foreign = self.write("cost_model.json", {"format": "raylab-cost-model", "version": 1, "claims": []})
        self.assert_refused(self.run_tool(foreign, good), "not a raylab results file")
        self.assert_refused(self.run_tool(good, self.write("list.json", "[1, 2]")), "not a raylab results file")
        newer = dict(results([]), version=2)
        self.assert_refused(self.run_tool(good, self.write("newer.json", newer)), "version")


if __name__ == "__main__":
    unittest.main()
