#!/usr/bin/python3
"""Compares two raylab results files (docs/results/results.json, written by make_report.py):

    compare_results.py A.json B.json [--json]

A is the reference (e.g. the published report), B the new one (e.g. a report made on your
machine). Lists the key numbers of B that lie outside A's 95% interval, the claims whose verdict
differs, the key numbers whose spec differs (a changed default shows up here), and the claims
present in only one file; ends with a summary line: "N of M key numbers of B inside A's 95%
interval; verdicts identical: yes/no". With --json the same as one JSON object.

A file that is not valid JSON, not a raylab results file (format "raylab-results") or of an
unknown version gives one line `compare_results: error: ...` and exit status 2. Exit status 0
otherwise, whatever the differences."""
import json
import math
import pathlib
import sys

FORMAT = "raylab-results"
VERSION = 1


class ResultsError(Exception):
    """A file compare_results cannot read as a raylab results file."""


def load_results(path) -> dict:
    """The parsed results file at `path`; ResultsError naming the fault otherwise."""
    try:
        text = pathlib.Path(path).read_text()
    except OSError as e:
        raise ResultsError(f"{path}: cannot read: {e.strerror}") from None
    return parse_results(text, str(path))


def parse_results(text: str, name: str) -> dict:
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        raise ResultsError(f"{name}: not JSON ({e.msg} at line {e.lineno})") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise ResultsError(f"{name}: not a raylab results file (format is not \"{FORMAT}\")")
    if data.get("version") != VERSION:
        raise ResultsError(f"{name}: results format version {data.get('version')!r}; this tool reads {VERSION}")
    claims = data.get("claims")
    if not isinstance(claims, list):
        raise ResultsError(f"{name}: \"claims\" is not a list")
    for i, c in enumerate(claims + list(data.get("numbers") or [])):
        if not isinstance(c, dict) or not isinstance(c.get("id"), str):
            raise ResultsError(f"{name}: entry {i} of claims/numbers has no string \"id\"")
        key = c.get("key")
        if key is not None and (not isinstance(key, dict) or not _is_interval(key.get("ci95"))):
            raise ResultsError(f"{name}: claim {c['id']}: \"key\" needs \"ci95\": [lo, hi]")
    return data


def _is_interval(v) -> bool:
    return isinstance(v, list) and len(v) == 2 and all(x is None or isinstance(x, (int, float)) for x in v)


def _number(x):
    """A JSON number as a float; None (JSON null, NaN written by make_report) stays None."""
    return None if x is None or (isinstance(x, float) and math.isnan(x)) else float(x)


def entries(data: dict) -> dict:
    """id -> entry over claims and other numbers; numbers are keyed "number:<id>"."""
    out = {c["id"]: c for c in data["claims"]}
    for n in data.get("numbers") or []:
        out["number:" + n["id"]] = n
    return out


def compare(a: dict, b: dict) -> dict:
    """The differences of B from A (see the module's doc)."""
    ea, eb = entries(a), entries(b)
    moved, flipped, specs, inside, total = [], [], [], 0, 0
    for cid, ca in ea.items():
        cb = eb.get(cid)
        if cb is None:
            continue
        if "verdict" in ca and ca.get("verdict") != cb.get("verdict"):
            flipped.append({"id": cid, "a": ca.get("verdict"), "b": cb.get("verdict")})
        ka, kb = ca.get("key"), cb.get("key")
        if not ka or not kb:
            continue
        if (ka.get("spec") or "") != (kb.get("spec") or ""):
            specs.append({"id": cid, "name": kb.get("name"), "a": ka.get("spec"), "b": kb.get("spec")})
        value = _number(kb.get("value"))
        lo, hi = (_number(x) for x in ka["ci95"])
        if value is None or lo is None or hi is None:
            continue
        total += 1
        if lo <= value <= hi:
            inside += 1
        else:
            moved.append({"id": cid, "name": kb.get("name") or ka.get("name"), "a": _number(ka.get("value")),
                          "ci95": [lo, hi], "b": value})
    only_a = sorted(set(ea) - set(eb))
    only_b = sorted(set(eb) - set(ea))
    return {"a_revision": a.get("revision"), "b_revision": b.get("revision"), "moved": moved, "flipped": flipped,
            "changed_specs": specs, "only_in_a": only_a, "only_in_b": only_b, "inside": inside, "compared": total,
            "verdicts_identical": not flipped and not [c for c in only_a + only_b if not c.startswith("number:")]}


def summary_line(d: dict) -> str:
    return (f"{d['inside']} of {d['compared']} key numbers of B inside A's 95% interval; verdicts identical: "
            f"{'yes' if d['verdicts_identical'] else 'no'}")


def report_lines(d: dict) -> list:
    lines = [f"A: revision {d['a_revision']}; B: revision {d['b_revision']}"]
    for m in d["moved"]:
        lines.append(f"moved: {m['id']} {m['name']}: {m['a']:.6g} [{m['ci95'][0]:.6g}, {m['ci95'][1]:.6g}] -> "
                     f"{m['b']:.6g}")
    for f in d["flipped"]:
        lines.append(f"flipped: {f['id']}: {f['a']} -> {f['b']}")
    for s in d["changed_specs"]:
        lines.append(f"spec changed: {s['id']} {s['name']}: {s['a']} -> {s['b']}")
    for c in d["only_in_a"]:
        lines.append(f"only in A: {c}")
    for c in d["only_in_b"]:
        lines.append(f"only in B: {c}")
    return lines + [summary_line(d)]


def main(argv) -> int:
    args = [a for a in argv if a != "--json"]
    if len(args) != 2 or any(a.startswith("-") for a in args):
        print("usage: compare_results.py A.json B.json [--json]", file=sys.stderr)
        return 2
    try:
        a, b = load_results(args[0]), load_results(args[1])
    except ResultsError as e:
        print(f"compare_results: error: {e}", file=sys.stderr)
        return 2
    d = compare(a, b)
    if "--json" in argv:
        print(json.dumps(d, indent=1))
    else:
        print("\n".join(report_lines(d)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
