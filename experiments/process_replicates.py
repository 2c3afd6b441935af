#!/usr/bin/python3
"""A claim's key number replicated in separate processes.

Some key numbers are timed slopes (claim 4's sort/events slope, claim 7c's traversal-share slope):
within one process their replicate rounds agree closely, yet a rerun in another process, at
another point of the report, moves them far outside that interval (allocation, page placement and
the machine's load differ between processes, and every round of one process shares them). For
those claims `./lab report` runs the deciding experiment again, `--claim ID`, in separate
processes after all the others, into <results>/process_replicates/claim-ID/run-K/. Here the first
process's value and the replicates' are combined:

  value = the mean over the n processes; 95% interval = mean ± t(0.975, n − 1)·s/√n, s the
  standard deviation between processes (Student's t: n is small);

and the verdict is decided again from that interval by the claim's own rule (decide_verdict in
experiments/experiment_common.h; directions below, above, within). Where a process estimates its
own threshold (claim 4's k/2), the most demanding one decides: the largest for `above`, the
smallest for `below`.

Every replicate must be the same claim with the same spec and rule as the first process's row;
anything else (a stale directory, a foreign file) raises ReplicateError."""
import csv
import math
import pathlib
import statistics

# Student's t(0.975, dof) for dof = 1 … 10.
T975 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306, 9: 2.262, 10: 2.228}

CONFIRMED, REFUTED, INCONCLUSIVE = "confirmed", "refuted", "inconclusive at this noise"


class ReplicateError(Exception):
    pass


def number(row, field, where) -> float:
    try:
        x = float(row.get(field, ""))
    except ValueError:
        x = math.nan
    if not math.isfinite(x):
        raise ReplicateError(f"{where}: field {field} is not a finite number ({row.get(field)!r})")
    return x


def replicate_rows(out: pathlib.Path, claim: str) -> list:
    """The claim's verdict rows from out/process_replicates/claim-ID/run-*/*.verdicts.csv, in run
    order; [] when the claim was not replicated."""
    rows = []
    base = out / "process_replicates" / f"claim-{claim}"
    for run in sorted(base.glob("run-*"), key=lambda p: (len(p.name), p.name)):
        found = []
        for path in sorted(run.glob("*.verdicts.csv")):
            with path.open(newline="") as f:
                found += [dict(r, path=str(path)) for r in csv.DictReader(f) if r.get("claim") == claim]
        if len(found) != 1:
            raise ReplicateError(f"{run}: expected one verdict row of claim {claim}, found {len(found)}")
        rows.append(found[0])
    return rows


def decide(lo: float, hi: float, direction: str, value: float, tolerance: float) -> str:
    """decide_verdict of experiment_common.h."""
    if not lo <= hi:
        return INCONCLUSIVE
    if direction == "below":
        return CONFIRMED if hi < value else REFUTED if lo > value else INCONCLUSIVE
    if direction == "above":
        return CONFIRMED if lo > value else REFUTED if hi < value else INCONCLUSIVE
    if direction == "within":
        if lo > value - tolerance and hi < value + tolerance:
            return CONFIRMED
        return REFUTED if lo >= value + tolerance or hi <= value - tolerance else INCONCLUSIVE
    raise ReplicateError(f"threshold direction {direction!r} cannot be decided from one key number")


def fmt(x: float) -> str:
    return f"{x:.4g}"


def combine(first: dict, replicates: list):
    """The first process's verdicts.csv row with its key number, interval, replicate count, threshold
    and verdict replaced by the combination over all processes, and the Markdown that shows the
    processes one by one. `replicates` are the other processes' rows of the same claim."""
    claim = first["claim"]
    rows = [first] + replicates
    for r in replicates:
        where = r.get("path", "replicate")
        for field in ("claim", "spec", "key_name", "threshold_direction", "threshold_tolerance"):
            if r.get(field, "") != first.get(field, ""):
                raise ReplicateError(f"{where}: {field} {r.get(field)!r} differs from the first process's "
                                     f"{first.get(field)!r}")
    direction = first.get("threshold_direction", "")
    values = [number(r, "key_value", r.get("path", "first process")) for r in rows]
    thresholds = [number(r, "threshold_value", r.get("path", "first process")) for r in rows]
    n = len(values)
    if n < 2:
        raise ReplicateError(f"claim {claim}: at least two processes are needed, got {n}")
    if n - 1 not in T975:
        raise ReplicateError(f"claim {claim}: {n} processes; at most {max(T975) + 1} are supported")
    mean, sd = statistics.fmean(values), statistics.stdev(values)
    half = T975[n - 1] * sd / math.sqrt(n)
    lo, hi = mean - half, mean + half
    threshold = max(thresholds) if direction == "above" else min(thresholds) if direction == "below" else thresholds[0]
    if direction == "within" and any(t != thresholds[0] for t in thresholds):
        raise ReplicateError(f"claim {claim}: the processes' targets differ: {thresholds}")
    tolerance = number(first, "threshold_tolerance", "first process") if direction == "within" else math.nan
    verdict = decide(lo, hi, direction, threshold, tolerance)
    row = dict(first)
    row.update(key_value=repr(mean), ci95_lo=repr(lo), ci95_hi=repr(hi), replicates=str(n),
               threshold_value=repr(threshold), verdict=verdict,
               interval=f"95% t-interval over {n} separate processes: mean ± t(0.975, {n - 1})·s/√{n}, s the standard "
                        "deviation between the processes' values (each process's own interval is in the section)",
               key=f"mean over {n} processes {fmt(mean)} [{fmt(lo)}, {fmt(hi)}] (processes: "
                   f"{', '.join(fmt(v) for v in values)}); first process: {first['key']}")
    md = [f'<a id="process-replicates-{claim}"></a>', "",
          f"**Claim {claim} across {n} separate processes.** Within one process the replicate rounds share its "
          "allocation, page placement and load, so a rerun can land outside that process's interval. `./lab report` "
          f"therefore runs `{first.get('command') or 'the experiment'}` {n - 1} more times, each in its own process "
          "after every other experiment; the verdict in the summary table is decided by the rule above from the "
          f"interval over the processes (mean ± t(0.975, {n - 1})·s/√{n})"
          + (", against the most demanding of the processes' thresholds" if len(set(thresholds)) > 1 else "") + ".", "",
          "| process | key number | its own 95% interval | threshold |", "|---|---|---|---|"]
    for i, r in enumerate(rows):
        own = [r.get("ci95_lo", ""), r.get("ci95_hi", "")]
        try:
            own_cell = f"[{fmt(float(own[0]))}, {fmt(float(own[1]))}]"
        except ValueError:
            own_cell = "–"
        md.append(f"| {i + 1} | {fmt(values[i])} | {own_cell} | {fmt(thresholds[i])} |")
    md += ["", f"Over the {n} processes: **{fmt(mean)} [{fmt(lo)}, {fmt(hi)}]** against {direction} {fmt(threshold)}: "
           f"**{verdict}** (first process alone: {first['verdict']}).", ""]
    return row, "\n".join(md)


def insert_after_verdict(section: str, claim: str, md: str) -> str:
    """The section's Markdown with `md` as a paragraph after the claim's verdict paragraph (the one
    holding its anchor verdict-ID), or at the end when it has none."""
    anchor = section.find(f'<a id="verdict-{claim}"></a>')
    end = section.find("\n\n", anchor) if anchor >= 0 else -1
    if end < 0:
        return section.rstrip() + "\n\n" + md.rstrip()
    return section[:end] + "\n\n" + md.rstrip() + section[end:]
