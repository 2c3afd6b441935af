#!/usr/bin/python3
"""experiments/process_replicates.py and its use by make_report.py: a claim replicated in separate
processes gets the t-interval over the processes and the verdict that interval gives under the
claim's own rule, the most demanding of the processes' thresholds, and a table of the processes in
its section; a replicate of another spec or a run without the claim's row is refused with one
error line and exit status 2."""
import csv
import json
import math
import pathlib
import statistics
import subprocess
import sys
import tempfile
import unittest

EXPERIMENTS = pathlib.Path(__file__).resolve().parent.parent / "experiments"
sys.path.insert(0, str(EXPERIMENTS))
import process_replicates  # noqa: E402

FIELDS = ["claim", "title", "verdict", "key", "anchor", "key_name", "key_value", "ci95_lo", "ci95_hi", "replicates",
          "spec", "interval", "threshold", "threshold_direction", "threshold_value", "threshold_tolerance", "command"]


def row(value, lo, hi, threshold=0.2, direction="above", spec="kdtree:sweep=sort over kdtree:sweep=events",
        verdict="confirmed", tolerance=""):
    return {"claim": "4", "title": "build", "verdict": verdict, "key": f"b = {value}", "anchor": "claim-4",
            "key_name": "b", "key_value": str(value), "ci95_lo": str(lo), "ci95_hi": str(hi), "replicates": "9",
            "spec": spec, "interval": "bootstrap", "threshold": "b above k/2", "threshold_direction": direction,
            "threshold_value": str(threshold), "threshold_tolerance": tolerance,
            "command": "build/experiments/exp_spatial --mode quick --claim 4"}


def write_verdicts(path: pathlib.Path, rows):
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        for r in rows:
            w.writerow(r)


class Combine(unittest.TestCase):
    def test_mean_and_t_interval_over_the_processes(self):
        first, reps = row(0.45, 0.43, 0.46), [row(0.52, 0.46, 0.58), row(0.56, 0.51, 0.63)]
        combined, md = process_replicates.combine(first, reps)
        values = [0.45, 0.52, 0.56]
        mean, half = statistics.fmean(values), 4.303 * statistics.stdev(values) / math.sqrt(3)
        self.assertAlmostEqual(float(combined["key_value"]), mean, places=12)
        self.assertAlmostEqual(float(combined["ci95_lo"]), mean - half, places=12)
        self.assertAlmostEqual(float(combined["ci95_hi"]), mean + half, places=12)
        self.assertEqual(combined["replicates"], "3")
        self.assertEqual(combined["verdict"], "confirmed")
        self.assertIn("| 3 | 0.56 | [0.51, 0.63] | 0.2 |", md)
        self.assertIn('<a id="process-replicates-4"></a>', md)

    def test_verdict_follows_the_interval_over_processes_not_the_first_process(self):
        # The first process alone clears 0.2; the spread between processes does not.
        combined, _ = process_replicates.combine(row(0.45, 0.43, 0.46), [row(0.15, 0.1, 0.2), row(0.35, 0.3, 0.4)])
        self.assertEqual(combined["verdict"], "inconclusive at this noise")
        combined, _ = process_replicates.combine(row(0.05, 0.04, 0.06, verdict="refuted"),
                                                 [row(0.06, 0.05, 0.07), row(0.04, 0.03, 0.05)])
        self.assertEqual(combined["verdict"], "refuted")

    def test_the_most_demanding_threshold_decides(self):
        # Above: the largest of the processes' thresholds, 0.5, lies inside [0.4, 0.6]-ish.
        combined, _ = process_replicates.combine(row(0.50, 0.4, 0.6, threshold=0.1),
                                                 [row(0.51, 0.4, 0.6, threshold=0.5), row(0.52, 0.4, 0.6, threshold=0.2)])
        self.assertEqual(float(combined["threshold_value"]), 0.5)
        self.assertEqual(combined["verdict"], "inconclusive at this noise")
        combined, _ = process_replicates.combine(row(1.00, 0.9, 1.1, threshold=1.2, direction="below"),
                                                 [row(1.01, 0.9, 1.1, threshold=1.05, direction="below"),
                                                  row(1.02, 0.9, 1.1, threshold=1.3, direction="below")])
        self.assertEqual(float(combined["threshold_value"]), 1.05)
        self.assertEqual(combined["verdict"], "confirmed")

    def test_within(self):
        rows = [row(v, v - 0.001, v + 0.001, threshold=1.0, direction="within", tolerance="0.02")
                for v in (0.999, 1.001, 1.0)]
        self.assertEqual(process_replicates.combine(rows[0], rows[1:])[0]["verdict"], "confirmed")
        rows = [row(v, v - 0.001, v + 0.001, threshold=1.0, direction="within", tolerance="0.02")
                for v in (1.05, 1.06, 1.055)]
        self.assertEqual(process_replicates.combine(rows[0], rows[1:])[0]["verdict"], "refuted")

    def test_refuses_foreign_or_broken_replicates(self):
        with self.assertRaisesRegex(process_replicates.ReplicateError, "spec"):
            process_replicates.combine(row(0.45, 0.4, 0.5), [row(0.5, 0.4, 0.6, spec="kdtree:sweep=sort")])
        with self.assertRaisesRegex(process_replicates.ReplicateError, "not a finite number"):
            process_replicates.combine(row(0.45, 0.4, 0.5), [row("nan", 0.4, 0.6)])
        with self.assertRaisesRegex(process_replicates.ReplicateError, "threshold_tolerance"):
            process_replicates.combine(row(1.0, 0.9, 1.1, direction="within", tolerance="wide"),
                                       [row(1.0, 0.9, 1.1, direction="within", tolerance="wide")])
        with self.assertRaisesRegex(process_replicates.ReplicateError, "cannot be decided"):
            process_replicates.combine(row(0.45, 0.4, 0.5, direction="conditional"),
                                       [row(0.5, 0.4, 0.6, direction="conditional")])


PART_FIELDS = ["claim", "rule", "part", "name", "key_value", "ci95_lo", "ci95_hi", "replicates", "threshold_direction",
               "threshold_value", "threshold_tolerance"]


def parts(values, rule="conditional", names=("b", "sphereflake", "stadium"), threshold=1.1, direction="below"):
    """Verdict parts of claim 4's test row: one per value, the first named as the key number."""
    return [{"claim": "4", "rule": rule, "part": str(j), "name": names[j], "key_value": str(v),
             "ci95_lo": str(v - 0.001), "ci95_hi": str(v + 0.001), "replicates": "15", "threshold_direction": direction,
             "threshold_value": str(threshold), "threshold_tolerance": "nan"} for j, v in enumerate(values)]


def with_parts(value, part_values, **kw):
    first = row(value, value - 0.001, value + 0.001, threshold=1.1, direction="below")
    return dict(first, parts=parts(part_values, **kw))


class CombineParts(unittest.TestCase):
    """A claim decided from several parts (6a: one per scene; 7a: a precondition and a recovery) is
    decided again part by part over the processes, by the claim's own rule."""

    def test_conditional_rule_over_every_part(self):
        # The key part holds in every process; the second part crosses 1.1 in one process only, and its
        # interval over the processes straddles the threshold: the claim is undecided, although the
        # key number alone would confirm it.
        rows = [with_parts(1.00, [1.00, 1.05, 1.2]), with_parts(1.01, [1.01, 1.12, 1.2]),
                with_parts(1.00, [1.00, 1.06, 1.2])]
        combined, md = process_replicates.combine(rows[0], rows[1:])
        self.assertEqual(combined["verdict"], "inconclusive at this noise")
        self.assertNotIn("parts", combined)
        self.assertIn("| sphereflake | 1.05, 1.12, 1.06 |", md)
        # Every part decided, holding on two scenes and failing on the third: holds only under conditions.
        rows = [with_parts(1.00, [1.00, 1.05, 1.2]), with_parts(1.01, [1.01, 1.04, 1.21]),
                with_parts(1.00, [1.00, 1.06, 1.19])]
        self.assertEqual(process_replicates.combine(rows[0], rows[1:])[0]["verdict"],
                         "holds only under stated conditions")

    def test_gated_rule(self):
        def gated(first_values, second_values):
            rows = [with_parts(a, [a, b], rule="gated", names=("b", "recovery"), threshold=0.0, direction="above")
                    for a, b in zip(first_values, second_values)]
            for r in rows:
                r.update(threshold_value="0.0", threshold_direction="above")
            return process_replicates.combine(rows[0], rows[1:])[0]["verdict"]

        self.assertEqual(gated([0.06, 0.061, 0.059], [0.9, 1.0, 0.8]), "confirmed")
        self.assertEqual(gated([0.06, 0.061, 0.059], [-0.9, -1.0, -0.8]), "holds only under stated conditions")
        self.assertEqual(gated([-0.06, -0.061, -0.059], [0.9, 1.0, 0.8]), "refuted")
        self.assertEqual(gated([0.06, 0.061, 0.059], [0.9, -1.0, 0.8]), "inconclusive at this noise")

    def test_refuses_parts_that_differ_between_processes(self):
        rows = [with_parts(1.0, [1.0, 1.05]), with_parts(1.0, [1.0, 1.05, 1.2])]
        with self.assertRaisesRegex(process_replicates.ReplicateError, "verdict parts"):
            process_replicates.combine(rows[0], rows[1:])
        rows = [with_parts(1.0, [1.0, 1.05]), with_parts(1.0, [1.0, 1.05], rule="gated")]
        with self.assertRaisesRegex(process_replicates.ReplicateError, "rule"):
            process_replicates.combine(rows[0], rows[1:])
        rows = [with_parts(1.0, [1.0, 1.05], rule="majority"), with_parts(1.0, [1.0, 1.05], rule="majority")]
        with self.assertRaisesRegex(process_replicates.ReplicateError, "unknown verdict rule"):
            process_replicates.combine(rows[0], rows[1:])
        rows = [with_parts(1.0, [1.0, 1.05], names=("grass", "stadium")),
                with_parts(1.0, [1.0, 1.05], names=("grass", "stadium"))]
        with self.assertRaisesRegex(process_replicates.ReplicateError, "is not the key number"):
            process_replicates.combine(rows[0], rows[1:])
        rows = [row(1.0, 0.99, 1.01, threshold=1.1, direction="below"), with_parts(1.0, [1.0, 1.05])]
        with self.assertRaisesRegex(process_replicates.ReplicateError, "the first process none"):
            process_replicates.combine(rows[0], rows[1:])


class MakeReport(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.addCleanup(self.dir.cleanup)
        self.out = pathlib.Path(self.dir.name)
        write_verdicts(self.out / "spatial.verdicts.csv", [row(0.45, 0.43, 0.46)])
        (self.out / "spatial.md").write_text('## Spatial\n\n<a id="verdict-4"></a>**Verdict (claim 4): confirmed.** b.\n\n'
                                             "Measured by exp_spatial.\n")
        for k, v in ((2, 0.52), (3, 0.56)):
            write_verdicts(self.out / "process_replicates" / "claim-4" / f"run-{k}" / "spatial.verdicts.csv",
                           [row(v, v - 0.05, v + 0.05)])

    def make_report(self):
        return subprocess.run([sys.executable, str(EXPERIMENTS / "make_report.py"), str(self.out)], capture_output=True,
                              text=True, timeout=300)

    def test_report_decides_the_claim_over_the_processes(self):
        r = self.make_report()
        self.assertEqual(r.returncode, 0, r.stderr)
        page = (self.out / "README.md").read_text()
        summary = next(line for line in page.splitlines() if line.startswith("| 4. "))
        self.assertIn("n = 3", summary)
        self.assertIn("processes: 0.45, 0.52, 0.56", summary)
        # The processes' table follows the verdict paragraph, before the rest of the section.
        self.assertLess(page.index('<a id="verdict-4"></a>'), page.index('<a id="process-replicates-4"></a>'))
        self.assertLess(page.index('<a id="process-replicates-4"></a>'), page.index("Measured by exp_spatial."))
        key = next(c for c in json.loads((self.out / "results.json").read_text())["claims"] if c["id"] == "4")["key"]
        self.assertEqual(key["replicates"], 3)
        self.assertAlmostEqual(key["value"], statistics.fmean([0.45, 0.52, 0.56]), places=9)
        self.assertIn("separate processes", key["interval"])

    def test_a_replicate_of_another_spec_is_one_error(self):
        write_verdicts(self.out / "process_replicates" / "claim-4" / "run-3" / "spatial.verdicts.csv",
                       [row(0.5, 0.4, 0.6, spec="kdtree:sweep=events over kdtree:sweep=sort")])
        r = self.make_report()
        self.assertEqual(r.returncode, 2)
        self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
        self.assertIn("spec", r.stderr)
        self.assertFalse((self.out / "README.md").exists())

    def test_report_reads_the_verdict_parts_of_every_process(self):
        def write_parts(path, values):
            with path.open("w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=PART_FIELDS)
                w.writeheader()
                for p in parts(values, threshold=0.2, direction="above"):
                    w.writerow(p)

        write_parts(self.out / "spatial.verdict_parts.csv", [0.45, 0.1])
        for k in (2, 3):
            write_parts(self.out / "process_replicates" / "claim-4" / f"run-{k}" / "spatial.verdict_parts.csv",
                        [0.5, 0.11])
        r = self.make_report()
        self.assertEqual(r.returncode, 0, r.stderr)
        # b holds above 0.2 in every process, the second part fails everywhere: conditional by the rule,
        # although the key number alone would confirm the claim.
        claim = next(c for c in json.loads((self.out / "results.json").read_text())["claims"] if c["id"] == "4")
        self.assertEqual(claim["verdict_text"], "holds only under stated conditions")
        self.assertIn("| sphereflake | 0.1, 0.11, 0.11 |", (self.out / "README.md").read_text())
        # A replicate without its parts file is one error line.
        (self.out / "process_replicates" / "claim-4" / "run-3" / "spatial.verdict_parts.csv").unlink()
        r = self.make_report()
        self.assertEqual(r.returncode, 2)
        self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
        self.assertIn("verdict parts", r.stderr)

    def test_a_run_without_the_claims_row_is_one_error(self):
        write_verdicts(self.out / "process_replicates" / "claim-4" / "run-2" / "spatial.verdicts.csv", [])
        r = self.make_report()
        self.assertEqual(r.returncode, 2)
        self.assertIn("expected one verdict row of claim 4, found 0", r.stderr)


if __name__ == "__main__":
    unittest.main()
