#!/usr/bin/python3
"""coverage_check.py -- every branch of lib/src the suite never takes must be
listed in tests/coverage_exceptions.txt, with its reason.

  coverage_check.py <gcovr.json> <exceptions.txt> <source root>
  coverage_check.py --list <gcovr.json> <source root>   (the uncovered branches, as entries)

A branch is keyed so that the key survives line shifts: the file (relative to
lib/src), the function around it, the line's source text with its spaces
squeezed (and a `#k` when the same text occurs k > 1 times in the function),
and the branch's index among the line's branches as gcov numbers them (at -O0
one pair per condition, in the compiler's order).  Exception lines:

  file | function | branches | reason | source text[#k]

branches a comma-separated list of indices; the source text last, so that it
may hold any character.  The check fails (exit 1) when an uncovered branch is
not listed, or a listed entry names a line or branch that no longer exists; a
listed branch the suite now takes is reported (it should be removed from the
list) and also fails, unless --allow-covered is given.
"""
import json
import os
import re
import sys


def squeeze(text):
    return re.sub(r"\s+", " ", text.strip())


def load_report(path, root):
    """{key: count} for every branch of lib/src, key = (file, function, text, index)."""
    with open(path) as f:
        data = json.load(f)
    branches = {}
    for fobj in data["files"]:
        name = fobj["file"]
        rel = name.split("lib/src/", 1)[-1]
        src_path = name if os.path.isabs(name) else os.path.join(root, name)
        with open(src_path, encoding="utf-8") as sf:
            src = sf.read().split("\n")
        funcs = sorted((fn["lineno"], fn["name"]) for fn in fobj.get("functions", []))
        seen = {}
        # number every line's text within its function, in source order
        line_key = {}
        fi = -1
        for ln in range(1, len(src) + 1):
            while fi + 1 < len(funcs) and funcs[fi + 1][0] <= ln:
                fi += 1
            func = funcs[fi][1] if fi >= 0 else "-"
            text = squeeze(src[ln - 1])
            k = seen.get((func, text), 0) + 1
            seen[(func, text)] = k
            line_key[ln] = (func, text if k == 1 else "%s#%d" % (text, k))
        for line in fobj["lines"]:
            if line.get("gcovr/noncode"):
                continue
            for i, b in enumerate(line.get("branches", [])):
                func, text = line_key[line["line_number"]]
                key = (rel, func, text, i)
                branches[key] = branches.get(key, 0) + b["count"]
    return branches


def load_exceptions(path):
    entries = {}
    problems = []
    with open(path, encoding="utf-8") as f:
        for n, raw in enumerate(f, 1):
            line = raw.rstrip("\n")
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            parts = [p.strip() for p in line.split(" | ", 4)]
            if len(parts) != 5 or not parts[3] or not parts[4]:
                problems.append("%s:%d: want 'file | function | branches | reason | source text'" % (path, n))
                continue
            rel, func, idx, reason, text = parts
            try:
                indices = [int(x) for x in idx.split(",")]
            except ValueError:
                problems.append("%s:%d: bad branch list %r" % (path, n, idx))
                continue
            for i in indices:
                key = (rel, func, squeeze(text), i)
                if key in entries:
                    problems.append("%s:%d: listed twice: %s" % (path, n, fmt(key)))
                entries[key] = (n, reason)
    return entries, problems


def fmt(key):
    return "%s | %s | %d | %s" % (key[0], key[1], key[3], key[2])


def main(argv):
    allow_covered = "--allow-covered" in argv
    argv = [a for a in argv if a != "--allow-covered"]
    if len(argv) == 4 and argv[1] == "--list":
        branches = load_report(argv[2], argv[3])
        for key in sorted(k for k, c in branches.items() if c == 0):
            print("%s | %s | %d | ? | %s" % (key[0], key[1], key[3], key[2]))
        return 0
    if len(argv) != 4:
        print(__doc__.strip().split("\n\n")[1])
        return 2
    branches = load_report(argv[1], argv[3])
    entries, problems = load_exceptions(argv[2])
    uncovered = [k for k, c in branches.items() if c == 0]
    unlisted = sorted(k for k in uncovered if k not in entries)
    gone = sorted((n, k) for k, (n, _) in entries.items() if k not in branches)
    covered = sorted((n, k) for k, (n, _) in entries.items() if k in branches and branches[k] > 0)
    for p in problems:
        print("coverage: " + p)
    for k in unlisted:
        print("coverage: uncovered and not listed: %s" % fmt(k))
    for n, k in gone:
        print("coverage: %s:%d lists a branch that does not exist: %s" % (argv[2], n, fmt(k)))
    for n, k in covered:
        print("coverage: %s:%d lists a branch the suite takes (remove it): %s" % (argv[2], n, fmt(k)))
    total = len(branches)
    print("coverage: %d branches of lib/src, %d taken, %d not taken: %d listed as exceptions, %d unlisted"
          % (total, total - len(uncovered), len(uncovered), len(uncovered) - len(unlisted), len(unlisted)))
    bad = problems or unlisted or gone or (covered and not allow_covered)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
