#!/usr/bin/env python3
"""Fails when the project's own C, C++ and proto source has more lines longer than the column
limit of .clang-format (ColumnLimit, 100) than MAX_OVER, counted in characters (a UTF-8 'µ' or '≥'
is one column, as clang-format counts them).

MAX_OVER is 0: the tree was formatted whole by clang-format (`--sort-includes=false`: the C kernels
depend on their include order), so the check lists every line over the limit and fails on the first.
(It was a ratchet from 4,047 lines when the check came in, issue 38, to that format.)

The files are the ones git tracks (or, outside a checkout, every file under the root) ending in .c,
.cc, .h or .proto, except generated and vendored ones (EXCLUDED below). A line that cannot be
broken (a long URL or string in a test's golden data) is allowed by a trailing `// NOLINT(length)`.

  scripts/line_length.py [--root DIR]   the check (exit 1 lists the offenders, file:line: columns)
  scripts/line_length.py --self-test     shows that a planted long line fails and a short one passes
  clang-format -i --lines=N:N FILE       the mend for line N (what the offender's message suggests)

The ctests `line_length` and `line_length_self_test` (tests/CMakeLists.txt) run them.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

SUFFIXES = (".c", ".cc", ".h", ".proto")
EXCLUDED = ("build", "build-", "third_party/", "dashboard/dashboard_assets.h")
ALLOW = "// NOLINT(length)"
MAX_OVER = 0


def column_limit(root):
    try:
        with open(os.path.join(root, ".clang-format"), encoding="utf-8") as f:
            m = re.search(r"^ColumnLimit:\s*(\d+)", f.read(), re.M)
            if m:
                return int(m.group(1))
    except OSError:
        pass
    return 100


def files(root):
    try:
        names = subprocess.run(["git", "-C", root, "ls-files"], check=True, capture_output=True,
                               text=True).stdout.splitlines()
    except (OSError, subprocess.CalledProcessError):
        names = [os.path.relpath(os.path.join(d, f), root) for d, _, fs in os.walk(root) for f in fs]
    return sorted(n for n in names if n.endswith(SUFFIXES) and not n.startswith(EXCLUDED))


def offenders(root, limit):
    found = []
    for name in files(root):
        path = os.path.join(root, name)
        if not os.path.isfile(path):
            continue
        with open(path, encoding="utf-8", errors="replace") as f:
            for i, line in enumerate(f, 1):
                line = line.rstrip("\n")
                if len(line) > limit and not line.endswith(ALLOW):
                    found.append((name, i, len(line)))
    return found


def check(root, out=sys.stdout, max_over=MAX_OVER):
    limit = column_limit(root)
    found = offenders(root, limit)
    if len(found) > max_over:
        for name, i, n in found:
            print(f"{name}:{i}: {n} columns (limit {limit}): clang-format -i --lines={i}:{i} {name}",
                  file=out)
        print(f"line_length: {len(found)} line(s) over {limit} columns, {max_over} allowed "
              f"(MAX_OVER): format the new ones (git diff shows which)", file=out)
        return 1
    if len(found) < max_over:
        print(f"line_length: {len(found)} line(s) over {limit} columns: lower MAX_OVER in "
              f"scripts/line_length.py to {len(found)}", file=out)
        return 0
    print(f"line_length: {len(found)} line(s) over {limit} columns (MAX_OVER)", file=out)
    return 0


def self_test():
    with tempfile.TemporaryDirectory() as d:
        with open(os.path.join(d, ".clang-format"), "w", encoding="utf-8") as f:
            f.write("BasedOnStyle: Google\nColumnLimit: 20\n")
        with open(os.path.join(d, "a.cc"), "w", encoding="utf-8") as f:
            f.write("int x = 1;  // µµµµµ\n")  # 20 characters, more bytes: within
        with open(os.path.join(d, "b.txt"), "w", encoding="utf-8") as f:
            f.write("x" * 50 + "\n")  # not a source file
        with open(os.devnull, "w", encoding="utf-8") as sink:
            if check(d, sink, 0) != 0:
                print("self-test: a 20-column line (multi-byte) or a non-source file was refused")
                return 1
            with open(os.path.join(d, "c.h"), "w", encoding="utf-8") as f:
                f.write("int planted_long_line = 0;\n")
            if check(d, sink, 0) != 1:
                print("self-test: a planted 26-column line passed a 20-column limit")
                return 1
    print("self-test: a planted long line fails, a short multi-byte one passes")
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    ap.add_argument("--self-test", action="store_true")
    a = ap.parse_args()
    sys.exit(self_test() if a.self_test else check(os.path.abspath(a.root)))


if __name__ == "__main__":
    main()
