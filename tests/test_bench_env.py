#!/usr/bin/python3
"""The benchmark binaries' environment lists (experiments/bench_env.h): a scene or accelerator spec they
cannot use, in $RAYLAB_BENCH_BVH_SCENES, _SPECS, _BUILD_SCENES or _BUILD_SPECS, ends the binary before any
benchmark runs, with one `error:` line naming the variable and exit status 2.

Usage: test_bench_env.py BENCH_BVH BENCH_BVH_BUILD"""
import os
import subprocess
import sys
import unittest

BENCH_BVH, BENCH_BVH_BUILD = sys.argv[1:3] if len(sys.argv) >= 3 else ("build/experiments/bench_bvh",
                                                                         "build/experiments/bench_bvh_build")


class BenchEnv(unittest.TestCase):
    def refused(self, binary: str, variable: str, value: str) -> str:
        env = dict(os.environ, **{variable: value})
        run = subprocess.run([binary, "--benchmark_list_tests"], capture_output=True, text=True, env=env, timeout=120)
        self.assertEqual(run.returncode, 2, run.stdout + run.stderr)
        self.assertEqual(run.stdout, "")
        lines = run.stderr.strip().splitlines()
        self.assertEqual(len(lines), 1, run.stderr)
        self.assertTrue(lines[0].startswith(f"error: ${variable}: "), lines[0])
        return lines[0]

    def test_bad_scene_specs(self):
        self.assertIn("unknown scene kind", self.refused(BENCH_BVH, "RAYLAB_BENCH_BVH_SCENES", "nonsense:x"))
        self.assertIn("outside", self.refused(BENCH_BVH_BUILD, "RAYLAB_BENCH_BVH_BUILD_SCENES", "sphere:n=-3"))
        self.assertIn("no scene spec", self.refused(BENCH_BVH_BUILD, "RAYLAB_BENCH_BVH_BUILD_SCENES", ";;"))

    def test_bad_accelerator_specs(self):
        self.assertIn("optimize=bogus", self.refused(BENCH_BVH, "RAYLAB_BENCH_BVH_SPECS", "bvh;bvh:optimize=bogus"))
        self.assertIn("unknown accelerator", self.refused(BENCH_BVH_BUILD, "RAYLAB_BENCH_BVH_BUILD_SPECS", "nope"))

    def test_good_lists_name_their_benchmarks(self):
        env = dict(os.environ, RAYLAB_BENCH_BVH_BUILD_SCENES="sphere:n=80",
                   RAYLAB_BENCH_BVH_BUILD_SPECS="bvh;bvh:optimize=reinsert,optimize_budget=0.1")
        run = subprocess.run([BENCH_BVH_BUILD, "--benchmark_list_tests"], capture_output=True, text=True, env=env,
                             timeout=120)
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertEqual(run.stdout.split(), [
            "BM_BvhBuild/sphere:n=80/1/iterations:7", "BM_BvhBuild/sphere:n=80/2/iterations:7",
            "BM_BvhBuild/sphere:n=80/1/bvh:optimize=reinsert,optimize_budget=0.1/iterations:7",
            "BM_BvhBuild/sphere:n=80/2/bvh:optimize=reinsert,optimize_budget=0.1/iterations:7",
            "BM_SbvhBuild/sphere:n=80/2/iterations:5"])


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1])
