#!/usr/bin/python3
"""experiments/bvh_scale.py, run as a user runs it on the committed data of docs/bvh_scale: its tables
parse as Markdown and say what the data say (the twins' ratios, the bytes against Embree's and the
bench table's medians, recomputed here from runs.csv and the bench JSONs), and a missing or foreign
input gets one error line and exit status 2."""
import csv
import json
import pathlib
import statistics
import subprocess
import sys
import tempfile
import unittest

ROOT = pathlib.Path(__file__).resolve().parent.parent
TOOL = ROOT / "experiments" / "bvh_scale.py"
DATA = ROOT / "docs" / "bvh_scale"
sys.path.insert(0, str(ROOT / "tests"))
import check_markdown_tables  # noqa: E402


BENCH = [DATA / "bench_1e7.json", DATA / "bench_1e7_indexed.json", DATA / "bench_1e6_optimize.json",
         DATA / "bench_kernels.json"]
BUILD = [DATA / "build_1e6.json"]


def table_rows(md: str, header_start: str):
    """The rows (lists of cells) of every table whose header line starts with `header_start`."""
    lines = md.splitlines()
    rows = []
    for start in (i for i, line in enumerate(lines) if line.startswith(header_start)):
        for line in lines[start + 2:]:
            if not line.startswith("|"):
                break
            rows.append([c.strip() for c in line.strip("|").split("|")])
    return rows


def median(values):
    return statistics.median(float(v) for v in values)


class BvhScale(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.TemporaryDirectory()
        cls.out = pathlib.Path(cls.dir.name)
        run = subprocess.run([sys.executable, str(TOOL), str(DATA / "runs.csv"), str(cls.out), *map(str, BENCH + BUILD)],
                             capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        cls.md = (cls.out / "README.md").read_text()

    @classmethod
    def tearDownClass(cls):
        cls.dir.cleanup()

    def test_tables_parse(self):
        self.assertEqual(check_markdown_tables.main([str(self.out / "README.md")]), 0)

    def test_twin_ratios_are_the_data(self):
        rows = list(csv.DictReader(open(DATA / "runs.csv")))
        ratio = {}
        for r in rows:
            ratio[(r["scene"], r["accel"], r["ray_kind"], r["replicate"])] = \
                float(r["embree_ns_per_ray_min"]) / float(r["ns_per_ray_min"])
        table = table_rows(self.md, "| scene | triangles | comparison |")
        self.assertGreater(len(table), 0)
        self.assertEqual({cells[2].split(" / ")[0].strip("`") for cells in table},
                         {"bvh:nodes=quantized", "bvh:leaves=indexed", "bvh:leaves=indexed,nodes=quantized"})
        for cells in table:
            scene, base = cells[0], cells[2].split(" / ")[1].strip("`")
            twin = cells[2].split(" / ")[0].strip("`")
            for kind, cell in zip(["primary", "diffuse", "shadow"], cells[3:6]):
                reps = sorted({k[3] for k in ratio if k[:3] == (scene, base, kind)})
                expected = statistics.median(ratio[(scene, twin, kind, r)] / ratio[(scene, base, kind, r)]
                                             for r in reps)
                self.assertAlmostEqual(float(cell.split(" ")[0]), expected, delta=0.0051, msg=f"{scene} {kind}")

    def test_bytes_against_embree_are_the_data(self):
        rows = [r for r in csv.DictReader(open(DATA / "runs.csv")) if r["ray_kind"] == "diffuse"]
        table = table_rows(self.md, "| scene | triangles | structure | bytes/tri | Embree bytes/tri |")
        self.assertEqual(len(table), len({(r["scene"], r["accel"]) for r in rows}))
        highest = {}
        for cells in table:
            scene, accel = cells[0], cells[2].strip("`")
            mine = [r for r in rows if r["scene"] == scene and r["accel"] == accel]
            tris = float(mine[0]["primitives"])
            ratio = median(r["bytes"] for r in mine) / median(r["embree_bytes"] for r in mine)
            self.assertAlmostEqual(float(cells[3]), median(r["bytes"] for r in mine) / tris, delta=0.051)
            self.assertAlmostEqual(float(cells[5]), ratio, delta=0.0051, msg=f"{scene} {accel}")
            highest[accel] = max(highest.get(accel, 0.0), ratio)
        goal = table_rows(self.md, "| structure | highest / Embree |")
        self.assertEqual({cells[0].strip("`") for cells in goal}, set(highest))
        for cells in goal:
            accel = cells[0].strip("`")
            self.assertAlmostEqual(float(cells[1]), highest[accel], delta=0.0051)
            self.assertEqual(cells[3], "yes" if float(cells[1]) <= 0.5 else "no")

    def test_bench_table_is_the_json(self):
        runs = [b for path in BENCH for b in json.loads(path.read_text())["benchmarks"]
                if b.get("run_type") == "iteration" and b["run_name"].startswith("BM_BvhTrace/")]
        table = table_rows(self.md, "| scene | triangles | structure | rays | ratio to `embree`")
        self.assertEqual(len(table), len({b["run_name"] for b in runs}))
        for cells in table:
            scene, spec, kind = cells[0], cells[2].strip("`"), cells[3]
            values = [b["vs_embree_fast"] for b in runs if b["run_name"].startswith(f"BM_BvhTrace/{scene}/{kind}:")
                      and b["run_name"].split("/")[3] == spec]
            self.assertEqual(int(cells[5]), len(values))
            self.assertAlmostEqual(float(cells[4].split(" ")[0]), statistics.median(values), delta=0.0051)
            recorded = [b for b in runs if b["run_name"].startswith(f"BM_BvhTrace/{scene}/{kind}:")
                        and b["run_name"].split("/")[3] == spec and "bytes_per_tri" in b]
            if recorded:
                ours = median(b["bytes_per_tri"] for b in recorded)
                self.assertAlmostEqual(float(cells[7]), ours, delta=0.051)
                self.assertAlmostEqual(float(cells[8]), ours / median(b["embree_bytes_per_tri"] for b in recorded),
                                       delta=0.0051)

    def test_kernel_steps_are_the_json(self):
        runs = [b for b in json.loads((DATA / "bench_kernels.json").read_text())["benchmarks"]
                if b.get("run_type") == "iteration"]
        table = table_rows(self.md, "| scene | triangles | rays | certified / watertight")
        self.assertEqual(len(table), len({tuple(b["run_name"].split("/")[1:3]) for b in runs}))

        def ratio(scene, kind, slow, fast):
            vs = {spec: {b["repetition_index"]: b["vs_embree_fast"] for b in runs
                         if b["run_name"].startswith(f"BM_BvhTrace/{scene}/{kind}:") and b["run_name"].split("/")[3] == spec}
                  for spec in (slow, fast)}
            return statistics.median(vs[fast][r] / vs[slow][r] for r in vs[slow])

        for cells in table:
            scene, kind = cells[0], cells[2]
            for cell, (slow, fast) in zip(cells[3:6], [("bvh", "bvh:kernel=watertight"),
                                                       ("bvh:kernel=watertight", "bvh:robust=off"),
                                                       ("bvh", "bvh:robust=off")]):
                self.assertAlmostEqual(float(cell.split(" ")[0]), ratio(scene, kind, slow, fast), delta=0.0051,
                                       msg=f"{scene} {kind} {slow}")

    def test_build_table_is_the_json(self):
        runs = [b for path in BUILD for b in json.loads(path.read_text())["benchmarks"]
                if b.get("run_type") == "iteration"]
        table = table_rows(self.md, "| scene | triangles | structure | threads | ours ms |")
        self.assertEqual(len(table), len({b["run_name"] for b in runs}))
        for cells in table:
            scene, spec, threads = cells[0], cells[2].strip("`"), cells[3]
            prefix = "BM_SbvhBuild" if spec == "bvh:builder=spatial" else "BM_BvhBuild"
            name = f"{prefix}/{scene}/{threads}" + ("" if spec in ("bvh", "bvh:builder=spatial") else f"/{spec}")
            values = [b["vs_embree"] for b in runs if b["run_name"] == name + "/" + b["run_name"].split("/")[-1]]
            self.assertEqual(int(cells[7]), len(values), name)
            self.assertAlmostEqual(float(cells[6].split(" ")[0]), statistics.median(values), delta=0.0051)
            lo, hi = (float(x) for x in cells[6].split("[")[1].rstrip("]").split(", "))
            goal = 1.5 if "optimize=" in spec else 1.0 if spec == "bvh" else None
            self.assertEqual(cells[9], "–" if goal is None else f"≤ {goal}")
            expected = ("–" if goal is None else "yes" if hi <= goal else "no" if lo > goal
                        else "not shown at this noise")
            self.assertEqual(cells[10], expected, name)

    def test_two_thread_page_has_its_goals_and_command(self):
        with tempfile.TemporaryDirectory() as d:
            out = pathlib.Path(d) / "threads2"
            run = subprocess.run([sys.executable, str(TOOL), str(DATA / "runs_2threads.csv"), str(out),
                                  "--plan", "data/plans/bvh_scale_2threads.json"], capture_output=True, text=True)
            self.assertEqual(run.returncode, 0, run.stderr)
            md = (out / "README.md").read_text()
            self.assertIn("--plan data/plans/bvh_scale_2threads.json --threads 2 --out", md)
            self.assertIn("wall-clock time on 2 threads", md)
            goals = {cells[0]: cells[4] for cells in table_rows(md, "| comparison | rays | geometric mean")}
            self.assertEqual(goals, {"`bvh:robust=off` / `embree`": "≥ 1.1", "`bvh` / `embree`": "≥ 1.0"})
            # The single-thread page written beside it links it.
            run = subprocess.run([sys.executable, str(TOOL), str(DATA / "runs.csv"), d], capture_output=True, text=True)
            self.assertEqual(run.returncode, 0, run.stderr)
            self.assertIn("[2 threads](threads2/README.md)", (pathlib.Path(d) / "README.md").read_text())

    def test_geometric_means_are_the_data(self):
        for runs, page in ((DATA / "runs.csv", self.md), (DATA / "runs_2threads.csv", None)):
            if page is None:
                with tempfile.TemporaryDirectory() as d:
                    run = subprocess.run([sys.executable, str(TOOL), str(runs), d], capture_output=True, text=True)
                    self.assertEqual(run.returncode, 0, run.stderr)
                    page = (pathlib.Path(d) / "README.md").read_text()
            rows = list(csv.DictReader(open(runs)))
            for cells in table_rows(page, "| comparison | rays | geometric mean"):
                accel, kind = cells[0].split(" / ")[0].strip("`"), cells[1]
                per_rep = {}
                for r in rows:
                    if r["accel"] == accel and r["ray_kind"] == kind:
                        per_rep.setdefault(r["replicate"], []).append(
                            float(r["embree_ns_per_ray_min"]) / float(r["ns_per_ray_min"]))
                means = [statistics.geometric_mean(v) for v in per_rep.values()]
                self.assertAlmostEqual(float(cells[2].split(" ")[0]), statistics.median(means), delta=0.0051,
                                       msg=f"{runs.name} {accel} {kind}")

    def refused(self, *args):
        run = subprocess.run([sys.executable, str(TOOL), *args], capture_output=True, text=True)
        self.assertEqual(run.returncode, 2, run.stderr)
        self.assertEqual(len(run.stderr.strip().splitlines()), 1, run.stderr)
        return run.stderr

    def test_refuses_missing_and_foreign_inputs(self):
        with tempfile.TemporaryDirectory() as d:
            self.assertIn("no such file", self.refused(str(pathlib.Path(d) / "none.csv"), d))
            self.assertIn("not a bench_bvh or bench_bvh_build JSON",
                          self.refused(str(DATA / "runs.csv"), d, str(DATA / "runs.csv")))
            mixed = pathlib.Path(d) / "mixed.csv"
            mixed.write_text((DATA / "runs.csv").read_text() +
                             "".join((DATA / "runs_2threads.csv").read_text().splitlines(keepends=True)[1:]))
            self.assertIn("thread counts", self.refused(str(mixed), d))
            empty = pathlib.Path(d) / "empty.json"
            empty.write_text('{"benchmarks": []}')
            self.assertIn("not a bench_bvh or bench_bvh_build JSON", self.refused(str(DATA / "runs.csv"), d, str(empty)))


if __name__ == "__main__":
    unittest.main()
