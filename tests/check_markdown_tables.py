#!/usr/bin/python3
"""Checks that every Markdown table in the given files and directories (*.md, recursively) renders:
a table is a run of lines starting with '|'; its second line must be the header separator
(|---|...), every row must have the header's column count, and no row may hold '||' (rows written
on one line, joined by '||', render as one row). Escaped pipes (\\|) do not separate cells.

    check_markdown_tables.py PATH...

Prints one line per fault (file:line: what) and exits 1 if there is any, 0 otherwise."""
import pathlib
import re
import sys

SEPARATOR_CELL = re.compile(r"^\s*:?-{3,}:?\s*$")


def cells(line: str) -> list:
    """The cells of a table row: split at unescaped pipes, the outer ones dropped."""
    body = line.strip()
    if body.startswith("|"):
        body = body[1:]
    if body.endswith("|") and not body.endswith("\\|"):
        body = body[:-1]
    return re.split(r"(?<!\\)\|", body)


def table_faults(lines, name="<text>") -> list:
    """Faults of every table in `lines` (the text of one file, split into lines)."""
    faults = []
    i = 0
    in_code = False
    while i < len(lines):
        if lines[i].lstrip().startswith("```"):
            in_code = not in_code
        if in_code or not lines[i].lstrip().startswith("|"):
            i += 1
            continue
        start = i
        while i < len(lines) and lines[i].lstrip().startswith("|"):
            i += 1
        table = lines[start:i]
        header = cells(table[0])
        if len(table) < 2 or not all(SEPARATOR_CELL.match(c) for c in cells(table[1])):
            faults.append(f"{name}:{start + 1}: table without a header separator line (|---|...)")
        elif len(cells(table[1])) != len(header):
            faults.append(f"{name}:{start + 2}: separator has {len(cells(table[1]))} columns, header {len(header)}")
        for k, row in enumerate(table):
            if re.search(r"(?<!\\)\|\|", row):
                faults.append(f"{name}:{start + k + 1}: '||' in a row: rows joined on one line render as one")
            elif len(cells(row)) != len(header):
                faults.append(f"{name}:{start + k + 1}: {len(cells(row))} columns, the header has {len(header)}")
    return faults


def markdown_files(paths) -> list:
    files = []
    for p in map(pathlib.Path, paths):
        files += sorted(p.rglob("*.md")) if p.is_dir() else [p]
    return files


def main(argv) -> int:
    if not argv:
        print("usage: check_markdown_tables.py PATH...", file=sys.stderr)
        return 2
    faults = []
    for f in markdown_files(argv):
        faults += table_faults(f.read_text().splitlines(), str(f))
    for fault in faults:
        print(fault)
    return 1 if faults else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
