#!/usr/bin/python3
"""Every timing column of the report's CSVs comes with its interval and a replicate count (issue 30:
"every timing figure in docs/results/ has an interval and a replicate count").

A timing column is one whose name has the unit ns (`ns_per_ray`, `embree_ns_per_ray`, `ns_valid`) or
seconds (`build_s`, `choose_s`). Its interval is one of:
  - `X_lo` and `X_hi` (for `X_s` also `X_lo_s` and `X_hi_s`): a 95% interval;
  - for the fastest of several passes, `X_min` (or `build_s`), its slowest, `X_max` (`build_s_max`):
    the passes' range; a median `X_median` sits inside the range `X_min` to `X_max`; the columns of
    FASTEST_OF_PASSES are fastest passes whose slowest is `X_hi`.
The file must also name how many replicates stand behind it (REPLICATE_COLUMNS).

Columns that are not measured times are listed in NOT_MEASURED with the reason.

Usage: check_timing_intervals.py DIR...: prints one line per fault and exits 1 when there is any."""
import csv
import pathlib
import re
import sys

TIMING = re.compile(r"(^|_)ns(_|$)|_s$")
REPLICATE_COLUMNS = {"rounds", "replicates", "passes", "build_rounds", "measured_replicates"}
# file name -> column -> why it is not a measured time
NOT_MEASURED = {
    "cost_model.csv": {c: "a model's prediction" for c in ("counters_ns", "tree_ns", "sah80_ns", "sah15_ns")},
    "cost_memory.csv": {"counters_ns_per_visit": "the counters model's prediction"},
    "bvh_walls_fit.csv": {"fitted_ns_per_ray": "a fitted curve's value"},
    "certainty.csv": {"mrays_per_s": "10^3 / ns_per_ray, whose interval is ns_per_ray_lo..hi"},
}

# file name -> columns that are the fastest of their passes, with the slowest in X_hi
FASTEST_OF_PASSES = {"cost_memory.csv": {"measured_ns_per_visit"}}


def interval_of(column, columns, fastest_of_passes=()):
    """The columns that hold `column`'s interval or range, or None."""
    candidates = [(column + "_lo", column + "_hi")]
    if column.endswith("_s"):
        candidates.append((column[:-2] + "_lo_s", column[:-2] + "_hi_s"))
    if column.endswith("_min"):
        candidates.append((column, column[:-4] + "_max"))
    if column.endswith("_median"):
        candidates.append((column[:-7] + "_min", column[:-7] + "_max"))
    if column.endswith("_max"):
        candidates.append((column[:-4] + "_min", column))
    if column == "build_s":
        candidates.append(("build_s", "build_s_max"))
    if column in fastest_of_passes:
        candidates.append((column, column + "_hi"))
    for lo, hi in candidates:
        if lo in columns and hi in columns:
            return lo, hi
    return None


def faults_of(path):
    """One line per timing column of the CSV at `path` without an interval, and one when the file
    has timing columns but no replicate count."""
    path = pathlib.Path(path)
    with open(path, newline="") as f:
        header = next(csv.reader(f), [])
    columns = set(header)
    exempt = NOT_MEASURED.get(path.name, {})
    interval_ends = {c for c in header if re.search(r"_(lo|hi)(_s)?$", c)}
    timings = [c for c in header if TIMING.search(c) and c not in exempt and c not in interval_ends]
    faults = [f"{path}: {c}: a timing column without its interval (X_lo/X_hi, or the passes' X_min/X_max)"
              for c in timings if interval_of(c, columns, FASTEST_OF_PASSES.get(path.name, ())) is None]
    if timings and not columns & REPLICATE_COLUMNS:
        faults.append(f"{path}: timing columns but no replicate count (one of {', '.join(sorted(REPLICATE_COLUMNS))})")
    return faults


def main(dirs):
    faults = []
    for d in dirs:
        for path in sorted(pathlib.Path(d).glob("*.csv")):
            faults += faults_of(path)
    for f in faults:
        print(f)
    return 1 if faults else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
