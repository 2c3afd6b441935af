#!/usr/bin/python3
"""Builds the plots and the generated report page docs/results/README.md from the CSV files and
Markdown fragments the experiment binaries wrote. Run by `./lab report`; uses Debian's
/usr/bin/python3 (python3-matplotlib, python3-pandas).

Plots: every module experiments/plot_*.py has a function plot(out_dir: pathlib.Path) that
reads its experiment's CSV from out_dir (returning quietly when it is absent) and writes PNGs.

Verdicts: every experiment that tests a claim of the lecture writes <section>.verdicts.csv (claim,
title, verdict, key, anchor, then the structured key number and threshold; experiments/
experiment_common.h). The page opens with the machine it was measured on, a summary table of all
verdicts (each linking to its verdict paragraph, anchor verdict-<claim>) and the changes since the
last report, and closes with the list of verdicts, all generated here, never edited by hand.

results.json: the same verdicts with their key numbers, 95% intervals, replicates and full specs,
the machine, the noise floor (noise_floor.json, written by exp_noise_floor, when present) and the
CPU single-thread timings ran on (timing_cpu/timing_cpu.json, by ./lab report, when present), in
the format compare_results.py reads. Before writing it, the results.json committed at HEAD (or the
file given by --previous) is compared with the new one, and every key number that left its
interval and every verdict that flipped is listed under "Changes since the last report" with its
cause: the spec changed, code changed (commits between the two revisions touching the experiment's
source or lib/), or noise (neither)."""
import argparse
import csv
import datetime
import importlib.util
import json
import math
import os
import re
import pathlib
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
sys.path.insert(0, str(pathlib.Path(__file__).parent))  # figures.py, shared by the plot modules

import compare_results  # noqa: E402  (the comparison of two results files, shared with the tool)
import process_replicates  # noqa: E402  (claims replicated in separate processes)
import timing_cpu  # noqa: E402  (the CPU single-thread timings ran on)

REPO = pathlib.Path(__file__).resolve().parent.parent

# Fragments in reading order: the noise floor, the claims in their order (1, 2, 3, 4, 5, 6, 7), then
# the cost model, robustness, speed and accuracy; any other *.md fragment follows alphabetically.
ORDER = ["noise_floor", "image_log_objects", "surface_area", "crofton", "spatial", "ray_shooting_bounds", "grids", "bvh",
         "cost_model", "robustness", "speed_accuracy", "oracle_agreement", "certainty"]

# The experiment whose source measures each verdicts file's claims, when not exp_<section>.cpp.
SOURCE = {"ray_shooting_bounds": "experiments/exp_image_log_objects.cpp"}

# The verdict strings of experiment_common.h, as results.json names them.
VERDICT_CLASS = {"confirmed": "confirmed", "refuted": "refuted", "holds only under stated conditions": "conditional",
                 "inconclusive at this noise": "inconclusive"}


def claim_key(claim: str):
    """Sorts "1", "1b", "2", "10" in numeric order, then by the letter."""
    m = re.match(r"(\d+)(.*)", claim)
    return (int(m.group(1)), m.group(2)) if m else (10 ** 6, claim)


def read_verdicts(out: pathlib.Path):
    """Every row of every *.verdicts.csv, in claim order; each row also names its section."""
    rows = []
    for path in sorted(out.glob("*.verdicts.csv")):
        section = path.name[:-len(".verdicts.csv")]
        with path.open(newline="") as f:
            for row in csv.DictReader(f):
                row["section"] = section
                rows.append(row)
    return sorted(rows, key=lambda r: claim_key(r["claim"]))


def as_float(text):
    """A CSV field as a float; None for an empty, non-numeric or NaN field."""
    try:
        x = float(text)
    except (TypeError, ValueError):
        return None
    return None if math.isnan(x) or math.isinf(x) else x


def claim_entry(v) -> dict:
    """A verdicts.csv row as results.json's claim entry."""
    entry = {"id": v["claim"], "title": v["title"], "verdict": VERDICT_CLASS.get(v["verdict"], v["verdict"]),
             "verdict_text": v["verdict"], "section": v["section"],
             "source": SOURCE.get(v["section"], f"experiments/exp_{v['section']}.cpp")}
    if v.get("threshold"):
        entry["threshold"] = {"text": v["threshold"], "direction": v.get("threshold_direction") or None,
                              "value": as_float(v.get("threshold_value")),
                              "tolerance": as_float(v.get("threshold_tolerance"))}
    else:
        entry["threshold"] = None
    if v.get("key_name"):
        entry["key"] = {"name": v["key_name"], "value": as_float(v.get("key_value")),
                        "ci95": [as_float(v.get("ci95_lo")), as_float(v.get("ci95_hi"))],
                        "replicates": int(as_float(v.get("replicates")) or 0), "spec": v.get("spec") or "",
                        "interval": v.get("interval") or ""}
    else:
        entry["key"] = None
    entry["key_text"] = v["key"]
    if v.get("command"):
        entry["command"] = v["command"]
    return entry


def read_numbers(out: pathlib.Path) -> list:
    """Other key numbers of the sections, from *.numbers.csv (id, name, value, ci95_lo, ci95_hi,
    replicates, spec), in results.json's form."""
    numbers = []
    for path in sorted(out.glob("*.numbers.csv")):
        with path.open(newline="") as f:
            for r in csv.DictReader(f):
                numbers.append({"id": r["id"], "key": {
                    "name": r.get("name", ""), "value": as_float(r.get("value")),
                    "ci95": [as_float(r.get("ci95_lo")), as_float(r.get("ci95_hi"))],
                    "replicates": int(as_float(r.get("replicates")) or 0), "spec": r.get("spec") or ""}})
    return numbers


def significant_digits(x, lo, hi) -> int:
    """Enough significant digits to resolve the interval's width (at least 3)."""
    scale, width = max(abs(x), abs(lo), abs(hi)), hi - lo
    return min(10, max(3, math.ceil(math.log10(scale / width)) + 2)) if width > 0 and scale > 0 else 3


def interval_cell(v) -> str:
    lo, hi, x = as_float(v.get("ci95_lo")), as_float(v.get("ci95_hi")), as_float(v.get("key_value"))
    if x is None:
        return "–"
    if lo is None or hi is None:
        return f"{x:.4g} (no interval)"
    d = significant_digits(x, lo, hi)
    return f"{x:.{d}g} [{lo:.{d}g}, {hi:.{d}g}], n = {v.get('replicates', '?')}"


def summary_table(verdicts, anchors) -> list:
    """The table that opens the page; each row links to its claim's verdict paragraph where the
    fragments have its anchor (verdict-<claim>), else to its section."""
    if not verdicts:
        return []
    def cell(text: str) -> str:
        return text.replace("|", "\\|")

    lines = ["| claim | verdict | key number | 95% interval | verdict and section |", "|---|---|---|---|---|"]
    for v in verdicts:
        target = f"verdict-{v['claim']}" if f"verdict-{v['claim']}" in anchors else v["anchor"]
        lines.append(f"| {v['claim']}. {cell(v['title'])} | **{v['verdict']}** | {cell(v['key'])} | "
                     f"{cell(interval_cell(v))} | [verdict](#{target}) |")
    return lines + [""]


def run_text(cmd, cwd=REPO) -> str:
    """The first line of a command's output; "" when it cannot be run."""
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, cwd=cwd, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return ""
    return r.stdout.strip() if r.returncode == 0 else ""


def cache_sizes() -> dict:
    """Cache sizes of CPU 0 from sysfs (/sys/devices/system/cpu/cpu0/cache), else from getconf."""
    caches = {}
    for index in sorted(pathlib.Path("/sys/devices/system/cpu/cpu0/cache").glob("index*")):
        try:
            level = (index / "level").read_text().strip()
            kind = (index / "type").read_text().strip()
            size = (index / "size").read_text().strip()
        except OSError:
            continue
        caches["L" + level + {"Data": "d", "Instruction": "i"}.get(kind, "")] = size
    if caches:
        return caches
    for name, key in [("L1d", "LEVEL1_DCACHE_SIZE"), ("L1i", "LEVEL1_ICACHE_SIZE"), ("L2", "LEVEL2_CACHE_SIZE"),
                      ("L3", "LEVEL3_CACHE_SIZE")]:
        size = run_text(["getconf", key])
        if size.isdigit() and int(size) > 0:
            kib = int(size) // 1024
            caches[name] = f"{kib // 1024}M" if kib >= 1024 and kib % 1024 == 0 else f"{kib}K"
    return caches


def cpu_model() -> str:
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown"


def physical_cores():
    """Distinct (physical id, core id) pairs of /proc/cpuinfo; None when it does not say."""
    pairs, physical = set(), "0"
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            if key.strip() == "physical id":
                physical = value.strip()
            elif key.strip() == "core id":
                pairs.add((physical, value.strip()))
    except OSError:
        return None
    return len(pairs) or None


def compiler() -> str:
    """The C++ compiler of the build directory (build/CMakeCache.txt), else c++, with its version."""
    cxx = "c++"
    try:
        for line in (REPO / "build" / "CMakeCache.txt").read_text().splitlines():
            if line.startswith("CMAKE_CXX_COMPILER:"):
                cxx = line.split("=", 1)[1]
    except OSError:
        pass
    version = run_text([cxx, "--version"]).splitlines()
    return version[0] if version else cxx


def library_versions() -> dict:
    """Debian package versions of the libraries the measurements depend on."""
    versions = {}
    for name, package in [("CGAL", "libcgal-dev"), ("Embree", "libembree-dev"), ("Ceres", "libceres-dev"),
                          ("OpenMesh", "libopenmesh-dev"), ("TBB", "libtbb-dev")]:
        versions[name] = run_text(["dpkg-query", "-W", "-f=${Version}", package]) or "unknown"
    return versions


def machine_info() -> dict:
    return {"cpu": cpu_model(), "cores": physical_cores(), "threads": os.cpu_count(), "caches": cache_sizes(),
            "compiler": compiler(), "libraries": library_versions()}


def read_intervals(path: pathlib.Path, value: str, keep=lambda row: True) -> list:
    """(value, lo, hi) of column `value` and its `value`_lo / `value`_hi (or ratio_lo / ratio_hi for
    ratio_median) in the rows of CSV `path` that `keep` accepts; [] when the file or a column is
    missing or a cell is not a number."""
    lo_col, hi_col = ("ratio_lo", "ratio_hi") if value == "ratio_median" else (value + "_lo", value + "_hi")
    try:
        with open(path) as f:
            return [(float(r[value]), float(r[lo_col]), float(r[hi_col])) for r in csv.DictReader(f) if keep(r)]
    except (OSError, KeyError, TypeError, ValueError):
        return []


def certified_cost_sentence(structures: pathlib.Path) -> str:
    """exp_certainty's certified / watertight time per structure and ray kind (certainty_structures.csv),
    against the goal ≤ 1.10 decided row by row from each median's 95% interval."""
    rows = read_intervals(structures, "ratio_median")
    if not rows:
        return ""
    met = sum(hi <= 1.10 for _, _, hi in rows)
    above = sum(lo > 1.10 for _, lo, _ in rows)
    worst = max(rows)
    return (f" In this run it cost {min(rows)[0]:.2f}–{worst[0]:.2f}× the watertight kernel's time over every structure "
            f"and ray kind (medians of alternated rounds); against the goal ≤ 1.10, decided by each row's 95% interval: "
            f"{met} of {len(rows)} rows met it, {above} missed it and {len(rows) - met - above} straddle it (the highest "
            f"median {worst[0]:.3f} [{worst[1]:.3f}, {worst[2]:.3f}]; [certainty](certainty.md)).")


def default_bvh_against_embree_sentence(paths: pathlib.Path) -> str:
    """The default `bvh`'s throughput against Embree and Embree robust on exp_certainty's scenes
    (certainty.csv), each row the median of per-round ratios with its 95% interval."""
    def of_bvh(row):
        return row.get("accel") == "bvh" and row.get("rays") in ("primary", "diffuse", "shadow")
    fast = read_intervals(paths, "ratio_to_embree", of_bvh)
    robust = read_intervals(paths, "ratio_to_embree_robust", of_bvh)
    if not fast or not robust:
        return ""
    def span(rows):
        low, high = min(rows), max(rows)
        return (f"{low[0]:.2f} [{low[1]:.2f}, {low[2]:.2f}] to {high[0]:.2f} [{high[1]:.2f}, {high[2]:.2f}]")
    return (f" The default `bvh` reached {span(fast)} of Embree's throughput and {span(robust)} of Embree robust's "
            f"(lowest and highest of {len(fast)} scene and ray kind rows, primary, diffuse and shadow rays, single "
            "thread, each the median of alternated rounds with its 95% interval).")


def default_kernel_line(out: pathlib.Path) -> str:
    """What the default kernel guarantees, then what it cost in this run where the run has the data:
    exp_certainty's CSVs (certainty_structures.csv: every structure's certified over watertight
    time; certainty.csv: the BVH's paths and Embree on the same rays) and exp_speed_accuracy's
    (speed_accuracy.csv: each default against its kernel=watertight variant per scene family)."""
    text = ("**Defaults**: every accelerator traces with the certified kernel unless its spec names another: its "
            "first hit is the exact oracle's on every ray (touching, grazing, edge- and vertex-aimed rays "
            "included), held to 0 mismatches by the oracle suite.")
    structures, paths = out / "certainty_structures.csv", out / "certainty.csv"
    text += certified_cost_sentence(structures)
    text += default_bvh_against_embree_sentence(paths)
    chart = out / "speed_accuracy.csv"
    if chart.exists():
        # Certified (default) over watertight time per structure and scene family of the headline
        # chart: each structure's default against its `kernel=watertight` variant, same rays.
        throughput = {}
        with open(chart) as f:
            for r in csv.DictReader(f):
                if r.get("throughput_vs_embree") and r.get("family") and r.get("method"):
                    throughput[(r["family"], r["method"])] = float(r["throughput_vs_embree"])
        by_family = {}
        for (family, method), t in throughput.items():
            if ":" in method or "kernel" in method:
                continue
            twin = throughput.get((family, method + ":kernel=watertight"))
            if twin and t > 0:
                by_family.setdefault(family, []).append((twin / t, method))
        if by_family:
            parts = []
            for family, ratios in sorted(by_family.items()):
                lo, hi = min(ratios), max(ratios)
                parts.append(f"{family} {lo[0]:.2f}–{hi[0]:.2f} (`{hi[1]}` highest)")
            text += (" On the headline chart's scene families, the default structures' time over their "
                     "`kernel=watertight` variants' (primary, diffuse and shadow rays; "
                     "[speed against accuracy](speed_accuracy.md)): " + "; ".join(parts) + ".")
    return text


def read_json(path: pathlib.Path):
    """The JSON in `path`; None when absent or not JSON (the report's optional summaries:
    noise_floor.json at the start and the end, timing_cpu/timing_cpu.json)."""
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return None


# A drift of the noise floor's ratio between the start and the end of a run counts as a change of the
# machine's state beyond this fraction: half the 10% margin of the report's goals (certified / watertight
# <= 1.10, auto within 10%, claim 6a's t(3)/t(d*) < 1.10).
DRIFT_THRESHOLD = 0.05


def noise_floor_drift_line(start, end) -> str:
    """The noise floor measured again at the end of the run (noise_floor_end/, by ./lab report) against
    the one at its start: held (the intervals overlap), drifted (disjoint, the ratios within
    DRIFT_THRESHOLD of each other) or changed (beyond it). "" when either is missing."""
    if not start or not end:
        return ""
    try:
        r0, (r0_lo, r0_hi) = start["ratio"], start["ci95"]
        r1, (r1_lo, r1_hi) = end["ratio"], end["ci95"]
        ns0, ns1, e0, e1 = start["median_ns"], end["median_ns"], start["embree_median_ns"], end["embree_median_ns"]
        held = r1_lo <= r0_hi and r0_lo <= r1_hi
        drift = abs(r1 / r0 - 1.0)
    except (KeyError, TypeError, ValueError, ZeroDivisionError):
        return ""
    rule = (f"held when the two intervals overlap, drifted when they are disjoint but the ratios differ by at most "
            f"{100 * DRIFT_THRESHOLD:.0f}%, half the 10% margin of the report's goals; changed beyond")
    if held:
        verdict = "the machine's speed held: the two intervals overlap"
    elif drift <= DRIFT_THRESHOLD:
        verdict = (f"the machine's speed drifted by {100 * drift:.1f}%: the two intervals are disjoint, but the drift "
                   f"is within {100 * DRIFT_THRESHOLD:.0f}%")
    else:
        verdict = (f"**the machine's state changed during the run** ({100 * drift:.1f}%): timed figures from its start "
                   "and its end differ by more than their own intervals; compare them with care")
    verdict += f" (rule, stated before the figures: {rule})"
    return (f"**Noise floor at the start and at the end of this run** (`bvh` / `embree`, `cgal:bunny00`, diffuse rays): "
            f"{r0:.3f} [{r0_lo:.3f}, {r0_hi:.3f}] ({ns0:.0f} and {e0:.0f} ns/ray), then {r1:.3f} [{r1_lo:.3f}, "
            f"{r1_hi:.3f}] ({ns1:.0f} and {e1:.0f} ns/ray): {verdict} (`build/experiments/exp_noise_floor`, run "
            "first and last by `./lab report`).")


def machine_line(m: dict, revision: str) -> str:
    caches = ", ".join(f"{k} {v}" for k, v in m["caches"].items()) or "cache sizes unknown"
    libs = ", ".join(f"{k} {v}" for k, v in m["libraries"].items())
    cores = f"{m['cores']} cores, " if m.get("cores") else ""
    return (f"**Machine**: {m['cpu']}, {cores}{m['threads']} hardware threads ({caches}); compiler {m['compiler']}; "
            f"{libs} (Debian packages); commit measured {revision}.")


def closing_note(verdicts) -> list:
    if not verdicts:
        return []
    lines = ["## Verdicts", "", "Every claim of the lecture the report tests, with its verdict (the table at the top, as "
             "a list):", ""]
    for v in verdicts:
        lines.append(f"- **{v['claim']}. {v['title']}**: {v['verdict']} ({v['key']}).")
    return lines + [""]


def git_revision() -> str:
    return run_text(["git", "rev-parse", "HEAD"]) or "unknown"


def previous_results(path) -> dict:
    """The earlier results.json: `path` if given, else the one committed at HEAD; None if there is
    none or it cannot be read as one."""
    try:
        text = pathlib.Path(path).read_text() if path else run_text(["git", "show", "HEAD:docs/results/results.json"])
        return compare_results.parse_results(text, str(path or "HEAD:docs/results/results.json")) if text else None
    except (OSError, compare_results.ResultsError):
        return None


def commits_touching(a_rev: str, b_rev: str, paths) -> list:
    """Short hashes of the commits after a_rev up to b_rev that touch `paths`."""
    if not a_rev or not b_rev or a_rev == b_rev:
        return []
    out = run_text(["git", "log", "--format=%h", f"{a_rev}..{b_rev}", "--", *paths])
    return out.split() if out else []


def changes_section(previous, current) -> list:
    """"Changes since the last report": every verdict that flipped and every key number outside
    the previous interval, with its cause."""
    lines = ["## Changes since the last report", ""]
    if previous is None:
        return lines + ["No earlier results.json is committed: nothing to compare with.", ""]
    d = compare_results.compare(previous, current)
    lines.append(f"Against the report of revision {str(previous.get('revision'))[:12]}: {compare_results.summary_line(d)}.")
    lines.append("")
    claims_now = compare_results.entries(current)
    claims_then = compare_results.entries(previous)
    spec_changed = {s["id"]: s for s in d["changed_specs"]}
    rows = []
    for m in d["moved"]:
        lo, hi = m["ci95"]
        k = significant_digits(m["a"] if m["a"] is not None else m["b"], lo, hi)
        a = "–" if m["a"] is None else f"{m['a']:.{k}g}"
        rows.append((m["id"], f"key number {m['name']}: {a} [{lo:.{k}g}, {hi:.{k}g}] → {m['b']:.{k}g}"))
    rows += [(f["id"], f"verdict {f['a']} → {f['b']}") for f in d["flipped"]]
    rows += [(s["id"], "spec changed, number inside its interval")
             for s in d["changed_specs"] if s["id"] not in {r[0] for r in rows}]
    if not rows:
        return lines + ["Every verdict is unchanged and every key number lies inside its previous 95% interval.", ""]
    lines += ["| claim | change | cause |", "|---|---|---|"]
    for cid, what in rows:
        if cid in spec_changed:
            s = spec_changed[cid]
            cause = f"spec or default changed: `{s['a']}` → `{s['b']}`"
        else:
            source = (claims_now.get(cid) or claims_then.get(cid) or {}).get("source")
            commits = commits_touching(previous.get("revision"), current.get("revision"),
                                       [p for p in [source, "lib/"] if p])
            cause = (f"code changed: {', '.join(commits[:8])}{' …' if len(commits) > 8 else ''} touch "
                     f"{source or 'the experiment'} or lib/") if commits else "noise: neither the code nor the spec changed"
        lines.append(f"| {cid} | {what.replace('|', chr(92) + '|')} | {cause.replace('|', chr(92) + '|')} |")
    return lines + [""]


def results_json(verdicts, numbers, machine, noise_floor, revision) -> dict:
    return {"format": compare_results.FORMAT, "version": compare_results.VERSION, "revision": revision,
            "created": datetime.date.today().isoformat(), "machine": machine, "noise_floor": noise_floor,
            "claims": [claim_entry(v) for v in verdicts], "numbers": numbers}


def draw_figures(out: pathlib.Path) -> None:
    """Every experiments/plot_*.py draws its figures from the CSVs in `out`, into `out`."""
    for module_path in sorted(pathlib.Path(__file__).parent.glob("plot_*.py")):
        spec = importlib.util.spec_from_file_location(module_path.stem, module_path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        module.plot(out)


def main() -> int:
    parser = argparse.ArgumentParser(description="Builds the plots, docs/results/README.md and results.json.")
    parser.add_argument("results_dir")
    parser.add_argument("--previous", help="the earlier results.json to compare with (default: the one committed at "
                                           "HEAD)")
    parser.add_argument("--claim", help="a report of this one claim (`./lab report --claim ID`): its verdict alone in "
                                        "the summary and results.json, compared with the same claim of the earlier "
                                        "results.json")
    args = parser.parse_args()
    out = pathlib.Path(args.results_dir)
    if not out.is_dir():
        print(f"make_report.py: error: {out} is not a directory", file=sys.stderr)
        return 2
    draw_figures(out)
    fragments = {p.stem: p for p in out.glob("*.md") if p.name != "README.md"}
    names = [n for n in dict.fromkeys(ORDER) if n in fragments] + sorted(n for n in fragments if n not in ORDER)
    texts = {n: fragments[n].read_text().rstrip() for n in names}
    anchors = set(re.findall(r'<a id="([^"]+)"></a>', "\n".join(texts.values())))
    revision = git_revision()
    machine = machine_info()
    noise_floor = read_json(out / "noise_floor.json")
    noise_floor_end = read_json(out / "noise_floor_end" / "noise_floor.json")
    timing_cpu_summary = read_json(out / "timing_cpu" / "timing_cpu.json")
    verdicts = read_verdicts(out)
    try:
        for i, v in enumerate(verdicts):
            replicates = process_replicates.replicate_rows(out, v["claim"])
            if replicates:
                first = dict(v, parts=process_replicates.read_parts(out, v["claim"]))
                verdicts[i], md = process_replicates.combine(first, replicates)
                if v["section"] not in texts:
                    names.append(v["section"])
                texts[v["section"]] = process_replicates.insert_after_verdict(texts.get(v["section"], ""), v["claim"], md)
    except process_replicates.ReplicateError as e:
        print(f"make_report.py: error: {e}", file=sys.stderr)
        return 2
    numbers = read_numbers(out)
    if args.claim is not None:
        verdicts = [v for v in verdicts if v["claim"] == args.claim]
        if not verdicts:
            print(f"make_report.py: error: {out} holds no verdict of claim {args.claim}", file=sys.stderr)
            return 2
    results = results_json(verdicts, numbers, machine, noise_floor, revision)
    if noise_floor_end is not None:
        results["noise_floor_end"] = noise_floor_end
    if timing_cpu_summary is not None:
        results["timing_cpu"] = timing_cpu_summary
    previous = previous_results(args.previous)
    if args.claim is not None and previous is not None:
        kept = {n["id"] for n in numbers}
        previous = dict(previous, claims=[c for c in previous["claims"] if c["id"] == args.claim],
                        numbers=[n for n in previous.get("numbers") or [] if n["id"] in kept])
    title = "theory against practice" if args.claim is None else f"claim {args.claim}"
    page = [f"# raylab results: {title}", "",
            f"Generated by `./lab report` on {datetime.date.today().isoformat()} at git revision {revision[:12]}. "
            "Every number below comes from the experiment binary each section names; speed figures are single-thread "
            "unless stated, measured against Embree in the same process and run. The theory each claim comes from, "
            "with full citations and the threshold each verdict is decided by, is in [docs/theory.md](../theory.md). "
            "The same verdicts, key numbers, intervals and specs are in [results.json](results.json); "
            "`experiments/compare_results.py A.json B.json` compares two of them.", "",
            machine_line(machine, revision), ""]
    pinned = timing_cpu.header_line(timing_cpu_summary)
    page += [pinned, ""] if pinned else []
    drift = noise_floor_drift_line(noise_floor, noise_floor_end)
    page += [drift, ""] if drift else []
    page += [default_kernel_line(out), ""]
    page += summary_table(verdicts, anchors)
    page += changes_section(previous, results)
    for n in names:
        page.append(texts[n])
        page.append("")
    page += closing_note(verdicts)
    (out / "README.md").write_text("\n".join(page) + "\n")
    (out / "results.json").write_text(json.dumps(results, indent=1, ensure_ascii=False, allow_nan=False) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
