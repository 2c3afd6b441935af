#!/usr/bin/python3
"""A claim's key number replicated in separate processes.

Some key numbers are timed (claim 4's sort/events slope, 6a's t(3)/t(d*), 7a's slowdown slope b/a,
7c's traversal-share slope):
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

A claim whose verdict combines several decided parts (claim 6a: t(3)/t(d*) on each scene; 7a: the
slowdown and the recovery) lists them in <section>.verdict_parts.csv beside its verdict row
(write_verdicts in experiments/experiment_common.h), the first part being the key number. Then every
part is combined over the processes as above and decided by its own threshold, and the verdict is
the claim's rule applied to the parts' verdicts: "conditional" (decide_conditional) or "gated"
(decide_gated), as the experiment itself decides it.

Every replicate must be the same claim with the same spec, rule and parts as the first process's row;
anything else (a stale directory, a foreign file) raises ReplicateError."""
import csv
import math
import pathlib
import statistics

# Student's t(0.975, dof) for dof = 1 … 10.
T975 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306, 9: 2.262, 10: 2.228}

CONFIRMED, REFUTED, INCONCLUSIVE = "confirmed", "refuted", "inconclusive at this noise"
CONDITIONAL = "holds only under stated conditions"


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


def read_parts(directory: pathlib.Path, claim: str) -> list:
    """The claim's rows of directory/*.verdict_parts.csv in part order; [] when it has none."""
    parts = []
    for path in sorted(directory.glob("*.verdict_parts.csv")):
        with path.open(newline="") as f:
            parts += [dict(r, path=str(path)) for r in csv.DictReader(f) if r.get("claim") == claim]
    try:
        parts.sort(key=lambda r: int(r.get("part", "")))
    except ValueError:
        raise ReplicateError(f"{directory}: claim {claim}: a verdict part is not numbered") from None
    return parts


def replicate_rows(out: pathlib.Path, claim: str) -> list:
    """The claim's verdict rows from out/process_replicates/claim-ID/run-*/*.verdicts.csv, in run
    order, each with its verdict parts under "parts"; [] when the claim was not replicated."""
    rows = []
    base = out / "process_replicates" / f"claim-{claim}"
    for run in sorted(base.glob("run-*"), key=lambda p: (len(p.name), p.name)):
        found = []
        for path in sorted(run.glob("*.verdicts.csv")):
            with path.open(newline="") as f:
                found += [dict(r, path=str(path)) for r in csv.DictReader(f) if r.get("claim") == claim]
        if len(found) != 1:
            raise ReplicateError(f"{run}: expected one verdict row of claim {claim}, found {len(found)}")
        rows.append(dict(found[0], parts=read_parts(run, claim)))
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


def decide_conditional(cases: list) -> str:
    """decide_conditional of experiment_common.h."""
    if INCONCLUSIVE in cases:
        return INCONCLUSIVE
    if CONFIRMED in cases and REFUTED in cases:
        return CONDITIONAL
    return CONFIRMED if CONFIRMED in cases else REFUTED if REFUTED in cases else INCONCLUSIVE


def decide_gated(cases: list) -> str:
    """decide_gated of experiment_common.h: cases[0] must hold, the others decide between confirmed
    and holds only under stated conditions."""
    if not cases or INCONCLUSIVE in cases:
        return INCONCLUSIVE
    if cases[0] == REFUTED:
        return REFUTED
    return CONFIRMED if all(c == CONFIRMED for c in cases[1:]) else CONDITIONAL


RULES = {"conditional": decide_conditional, "gated": decide_gated}


def fmt(x: float) -> str:
    return f"{x:.4g}"


def key_values(rows: list):
    """The rows' key_value and threshold_value, one per process."""
    return ([number(r, "key_value", r.get("path", "first process")) for r in rows],
            [number(r, "threshold_value", r.get("path", "first process")) for r in rows])


def over_processes(claim: str, values: list, thresholds: list, direction: str, tolerance: float):
    """(mean, lo, hi, threshold, verdict) of one key number over the processes (`values`, with each
    process's threshold): the t-interval, the most demanding threshold, and the verdict that
    interval gives."""
    n = len(values)
    if n < 2:
        raise ReplicateError(f"claim {claim}: at least two processes are needed, got {n}")
    if n - 1 not in T975:
        raise ReplicateError(f"claim {claim}: {n} processes; at most {max(T975) + 1} are supported")
    mean, sd = statistics.fmean(values), statistics.stdev(values)
    half = T975[n - 1] * sd / math.sqrt(n)
    threshold = max(thresholds) if direction == "above" else min(thresholds) if direction == "below" else thresholds[0]
    if direction == "within" and any(t != thresholds[0] for t in thresholds):
        raise ReplicateError(f"claim {claim}: the processes' targets differ: {thresholds}")
    return mean, mean - half, mean + half, threshold, decide(mean - half, mean + half, direction, threshold, tolerance)


def combine_parts(claim: str, rows: list):
    """The verdict of a claim with verdict parts over the processes `rows` (each with its "parts"),
    and the Markdown table of its parts."""
    first = rows[0]["parts"]
    for r in rows:
        parts, where = r.get("parts") or [], r.get("path", "first process")
        if len(parts) != len(first):
            raise ReplicateError(f"{where}: claim {claim} has {len(parts)} verdict parts, the first process "
                                 f"{len(first)}")
        for a, b in zip(parts, first):
            for field in ("rule", "name", "threshold_direction", "threshold_tolerance"):
                if a.get(field, "") != b.get(field, ""):
                    raise ReplicateError(f"{a.get('path', where)}: verdict part {field} {a.get(field)!r} differs from "
                                         f"the first process's {b.get(field)!r}")
    rule = first[0].get("rule", "")
    if rule not in RULES:
        raise ReplicateError(f"{first[0].get('path', 'first process')}: claim {claim}: unknown verdict rule {rule!r}")
    if first[0].get("name") != rows[0].get("key_name"):
        raise ReplicateError(f"{first[0].get('path', 'first process')}: claim {claim}: the first verdict part "
                             f"{first[0].get('name')!r} is not the key number {rows[0].get('key_name')!r}")
    verdicts = []
    md = ["| part | processes | over the processes [95%] | threshold | verdict |", "|---|---|---|---|---|"]
    for j, part in enumerate(first):
        direction = part.get("threshold_direction", "")
        tolerance = number(part, "threshold_tolerance", part.get("path", "")) if direction == "within" else math.nan
        values, thresholds = key_values([r["parts"][j] for r in rows])
        mean, lo, hi, threshold, verdict = over_processes(claim, values, thresholds, direction, tolerance)
        verdicts.append(verdict)
        md.append(f"| {part['name']} | {', '.join(fmt(v) for v in values)} | "
                  f"{fmt(mean)} [{fmt(lo)}, {fmt(hi)}] | {direction} {fmt(threshold)} | {verdict} |")
    return RULES[rule](verdicts), md


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
    values, thresholds = key_values(rows)
    n = len(values)
    tolerance = number(first, "threshold_tolerance", "first process") if direction == "within" else math.nan
    mean, lo, hi, threshold, verdict = over_processes(claim, values, thresholds, direction, tolerance)
    parts_md = []
    if first.get("parts") or any(r.get("parts") for r in replicates):
        if not first.get("parts"):
            raise ReplicateError(f"claim {claim}: a replicate has verdict parts, the first process none")
        verdict, parts_md = combine_parts(claim, rows)
    row = {k: v for k, v in first.items() if k != "parts"}
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
    if parts_md:
        md += ["", f"The verdict combines the claim's parts, each over the {n} processes and decided by its own "
               f"threshold, by the rule \"{rows[0]['parts'][0]['rule']}\" (experiments/process_replicates.py):", ""]
        md += parts_md
        md += ["", f"Key number over the {n} processes: **{fmt(mean)} [{fmt(lo)}, {fmt(hi)}]**; claim verdict: "
               f"**{verdict}** (first process alone: {first['verdict']}).", ""]
    else:
        md += ["", f"Over the {n} processes: **{fmt(mean)} [{fmt(lo)}, {fmt(hi)}]** against {direction} "
               f"{fmt(threshold)}: **{verdict}** (first process alone: {first['verdict']}).", ""]
    return row, "\n".join(md)


def insert_after_verdict(section: str, claim: str, md: str) -> str:
    """The section's Markdown with `md` as a paragraph after the claim's verdict paragraph (the one
    holding its anchor verdict-ID), or at the end when it has none."""
    anchor = section.find(f'<a id="verdict-{claim}"></a>')
    end = section.find("\n\n", anchor) if anchor >= 0 else -1
    if end < 0:
        return section.rstrip() + "\n\n" + md.rstrip()
    return section[:end] + "\n\n" + md.rstrip() + section[end:]
