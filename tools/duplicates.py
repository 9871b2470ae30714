#!/usr/bin/env python3
"""Repeated blocks of six or more lines across the Rust sources.

Lines are compared with surrounding whitespace stripped; blank lines, lone
braces and brackets and `//` comments are skipped. A block is a maximal run of
lines that appears, in the same order, at two or more places (in one file or
in several). Prints each block's length and places, then the totals.

Usage: python3 tools/duplicates.py [ROOT]   (default: the current directory)
"""
import os
import sys
from collections import defaultdict

WINDOW = 6
TRIVIAL = {"", "{", "}", "};", "},", ")", ");", "),", "]", "];", "],", "})", "});"}


def sources(root):
    for d, dirs, files in os.walk(root):
        dirs[:] = [x for x in dirs if x not in ("target", ".git", "node_modules")]
        for f in files:
            if f.endswith(".rs"):
                yield os.path.join(d, f)


def significant(path):
    out = []
    with open(path, encoding="utf-8") as fh:
        for no, line in enumerate(fh, 1):
            s = line.strip()
            if s in TRIVIAL or s.startswith("//"):
                continue
            out.append((no, s))
    return out


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else "."
    files = {os.path.relpath(p, root): significant(p) for p in sources(root)}
    where = defaultdict(list)
    for f, lines in files.items():
        for i in range(len(lines) - WINDOW + 1):
            where[tuple(s for _, s in lines[i : i + WINDOW])].append((f, i))
    repeated = {k: v for k, v in where.items() if len(v) > 1}
    # Mark every line covered by a repeated window, then report maximal runs.
    covered = defaultdict(set)
    for places in repeated.values():
        for f, i in places:
            covered[f].update(range(i, i + WINDOW))
    blocks = []
    for f, idx in covered.items():
        run = []
        for i in sorted(idx) + [None]:
            if run and (i is None or i != run[-1] + 1):
                lines = files[f]
                blocks.append((f, lines[run[0]][0], lines[run[-1]][0], len(run)))
                run = []
            if i is not None:
                run.append(i)
    blocks.sort()
    for f, first, last, n in blocks:
        print(f"{f}:{first}-{last} ({n} lines)")
    total = sum(n for *_, n in blocks)
    print(f"{len(blocks)} repeated blocks, {total} lines, in {len(covered)} files")


if __name__ == "__main__":
    main()
