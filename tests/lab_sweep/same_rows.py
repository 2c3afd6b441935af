"""Exit 0 when two runs CSVs (raylab sweep, raylab merge) hold the same rows in the same order,
timing columns (and Embree's measured bytes) aside; otherwise name the first difference. Usage: same_rows.py A.csv B.csv"""
import csv
import sys

TIMING = {"passes", "ns_per_ray_min", "ns_per_ray_median", "ns_per_ray_max", "embree_ns_per_ray_min",
          "embree_ns_per_ray_max", "build_s", "build_s_max", "build_passes", "embree_bytes"}


def rows(path):
    with open(path, newline="") as f:
        return [{k: v for k, v in row.items() if k not in TIMING} for row in csv.DictReader(f)]


a, b = rows(sys.argv[1]), rows(sys.argv[2])
if len(a) != len(b):
    sys.exit(f"{sys.argv[1]}: {len(a)} rows, {sys.argv[2]}: {len(b)}")
for x, y in zip(a, b):
    if x != y:
        sys.exit(f"case {x['case']} differs in {[k for k in x if x[k] != y.get(k)]}")
