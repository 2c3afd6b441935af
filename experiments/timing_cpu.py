#!/usr/bin/env python3
"""Chooses the CPU that a report's single-thread timings run on (RAYLAB_TIMING_CPU).

On a virtual machine the vCPUs need not be equal: one may share its physical core with another
guest, and the same binary then traces 10-20% slower there, our structures more than Embree. So
`./lab report` first runs the noise floor's reference case (exp_noise_floor, quick) pinned to each
CPU the process may use, into DIR/cpu-K/, and this script picks the CPU on which our `bvh` traced
fastest (lowest median ns/ray). It writes DIR/timing_cpu.json (every CPU's figures and the choice)
and prints the chosen CPU's number for the caller to export.

Usage: timing_cpu.py DIR
"""
import json
import pathlib
import re
import sys

RULE = "the lowest median ns/ray of the noise floor's `bvh` (exp_noise_floor --mode quick, pinned to each CPU)"


class ProbeError(Exception):
    """A probe directory that cannot be read; its message is one line."""


def read_probes(directory: pathlib.Path) -> list:
    """One row per DIR/cpu-K/noise_floor.json, sorted by CPU."""
    rows = []
    for path in sorted(directory.glob("cpu-*/noise_floor.json")):
        match = re.fullmatch(r"cpu-(\d+)", path.parent.name)
        if not match:
            raise ProbeError(f"{path.parent}: expected a directory named cpu-K")
        try:
            j = json.loads(path.read_text())
            row = {"cpu": int(match.group(1)), "median_ns": float(j["median_ns"]),
                   "median_ns_ci95": [float(x) for x in j["median_ns_ci95"]],
                   "embree_median_ns": float(j["embree_median_ns"]), "ratio": float(j["ratio"]),
                   "ci95": [float(x) for x in j["ci95"]], "replicates": int(j["replicates"])}
        except (OSError, json.JSONDecodeError, KeyError, TypeError, ValueError) as e:
            raise ProbeError(f"{path}: not a noise_floor.json of exp_noise_floor ({e})") from None
        if not all(v > 0 for v in (row["median_ns"], row["embree_median_ns"], row["ratio"])):
            raise ProbeError(f"{path}: non-positive timing")
        rows.append(row)
    if not rows:
        raise ProbeError(f"{directory}: no cpu-K/noise_floor.json")
    return sorted(rows, key=lambda r: r["cpu"])


def choose(directory: pathlib.Path) -> dict:
    rows = read_probes(directory)
    best = min(rows, key=lambda r: r["median_ns"])
    return {"chosen": best["cpu"], "rule": RULE, "cpus": rows}


def header_line(summary) -> str:
    """The report header's sentence on where single-thread timings ran; "" without a summary."""
    if not summary:
        return ""
    try:
        rows, chosen = summary["cpus"], summary["chosen"]
        per_cpu = "; ".join(f"CPU {r['cpu']}: `bvh` {r['median_ns']:.0f} ns/ray [{r['median_ns_ci95'][0]:.0f}, "
                            f"{r['median_ns_ci95'][1]:.0f}], `embree` {r['embree_median_ns']:.0f}, throughput ratio "
                            f"{r['ratio']:.3f} [{r['ci95'][0]:.3f}, {r['ci95'][1]:.3f}]" for r in rows)
        slowest = max(r["median_ns"] for r in rows)
        fastest = min(r["median_ns"] for r in rows)
    except (KeyError, TypeError, ValueError, IndexError):
        return ""
    spread = (f"the slowest CPU took {slowest / fastest:.2f}× the fastest's time" if len(rows) > 1
              else "this process may use one CPU only")
    return (f"**Where single-thread timings ran**: CPU {chosen}, pinned for every timed single-thread section "
            f"(`RAYLAB_TIMING_CPU`, accel/common/timing_cpu.h). On a virtual machine the vCPUs need not be equal, "
            f"so `./lab report` first traced the noise floor's reference case on each CPU ({per_cpu}; {spread}) "
            f"and chose by {summary.get('rule', RULE)}. Multi-thread figures use every CPU.")


def main(argv) -> int:
    if len(argv) != 2:
        print("usage: timing_cpu.py DIR", file=sys.stderr)
        return 2
    directory = pathlib.Path(argv[1])
    try:
        summary = choose(directory)
    except ProbeError as e:
        print(f"timing_cpu.py: error: {e}", file=sys.stderr)
        return 2
    (directory / "timing_cpu.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(summary["chosen"])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
