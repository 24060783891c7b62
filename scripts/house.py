#!/usr/bin/env python3
"""Measures the house: the folders of the product's code, their lines, the includes between them
and the longest functions. A figure to compare before and after a move, not a check.

  scripts/house.py [--root DIR] [--longest N]

Counted: the .cc, .h and .c files git tracks, outside tests/, fuzz/, bench/, build trees and
generated files. A folder is the first path component (`model/kernels/x.h` is in `model/`).
An include between folders is an `#include "a/b.h"` whose first component names another folder.
Function lengths come from scripts/long_functions.py's scanner (signature to closing brace).
"""
import argparse
import collections
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import long_functions  # noqa: E402

LEFT_OUT = ("tests/", "fuzz/", "bench/", "build", "python/")
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def source_files(root):
    out = subprocess.run(["git", "-C", root, "ls-files", "*.cc", "*.h", "*.c"], check=True,
                         capture_output=True, text=True).stdout.split()
    return [f for f in out if not f.startswith(LEFT_OUT) and "/" in f]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    p.add_argument("--longest", type=int, default=10)
    a = p.parse_args()
    root = os.path.abspath(a.root)
    files = source_files(root)
    folders = sorted({f.split("/")[0] for f in files})
    lines = collections.Counter()
    edges = collections.Counter()
    functions = []
    for rel in files:
        with open(os.path.join(root, rel), encoding="utf-8", errors="replace") as fh:
            text = fh.read()
        folder = rel.split("/")[0]
        lines[folder] += text.count("\n")
        for inc in INCLUDE.findall(text):
            target = inc.split("/")[0]
            if target in folders and target != folder:
                edges[(folder, target)] += 1
        for name, first, last in long_functions.functions(text):
            functions.append((last - first + 1, rel, first, name))
    print(f"folders: {len(folders)}, files: {len(files)}, lines: {sum(lines.values())}")
    for folder in folders:
        outs = sorted(t for (s, t) in edges if s == folder)
        print(f"  {folder + '/':12} {lines[folder]:6} lines  includes {len(outs)} folder(s): "
              f"{' '.join(outs)}")
    print(f"includes between folders: {sum(edges.values())} lines over {len(edges)} folder pairs")
    functions.sort(reverse=True)
    over = sum(1 for f in functions if f[0] > long_functions.LIMIT)
    print(f"functions over {long_functions.LIMIT} lines: {over}; the {a.longest} longest:")
    for length, rel, first, name in functions[: a.longest]:
        print(f"  {length:4} {rel}:{first} {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
