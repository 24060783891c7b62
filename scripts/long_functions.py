#!/usr/bin/env python3
"""Lists the functions longer than a limit (120 lines) in every product folder (FOLDERS below:
model/, io/, opt/, job/, records/, controller/, hgann/, diagnose/, complete/, kinds/, service/,
master/, worker/, svcclient/, client/) and fails when one is not on the allow-list below.

A function's length is the number of lines from the first line of its signature to its closing
brace. The scan is a brace matcher over the source with comments, string and character literals
and preprocessor lines removed: a brace opened at namespace or class level after a parameter list
(or a qualifier such as `const`, `override`) opens a function body; lambdas and blocks inside a
function count as part of it; an initialiser (`= {...}`) is not a function.

  scripts/long_functions.py [--root DIR] [--limit N]   the check (exit 1 lists the offenders)
  scripts/long_functions.py --self-test                shows that a planted long function fails

The ctests `long_functions` and `long_functions_self_test` (tests/CMakeLists.txt) run them.
"""
import argparse
import os
import re
import sys
import tempfile

FOLDERS = ["model", "io", "opt", "job", "records", "controller", "hgann", "diagnose", "complete",
           "kinds", "service", "master", "worker", "svcclient", "reports", "dashboard", "client"]
LIMIT = 120

# Allowed long functions: (file or file prefix, function name or "*" for every function of the
# file), each with why. Keep it short: a long function that is not a table is split, not listed.
ALLOWED = [
]

FUNCTION_QUALIFIERS = {"const", "override", "final", "noexcept", "mutable", "try", "volatile", "&", "&&"}
CONTAINER = re.compile(r"^(?:template\s*<.*>\s*)?(?:namespace|class|struct|union|enum|extern\s*\"C\")\b", re.S)


def strip(text):
    """The source with comments, literals and preprocessor lines blanked (newlines kept)."""
    out = []
    i, n = 0, len(text)
    line_start = True
    while i < n:
        c = text[i]
        if line_start and c == "#":  # a preprocessor line, with its continuations
            j = i
            while j < n and not (text[j] == "\n" and text[j - 1] != "\\"):
                j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
            continue
        if c == "\n":
            line_start = True
            out.append(c)
            i += 1
            continue
        if not c.isspace():
            line_start = False
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "R" and text.startswith('"', i + 1) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            end = text.find(")" + m.group(1) + '"', i) if m else -1
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append('""' + re.sub(r"[^\n]", " ", text[i + 2:j]))
            i = j
        elif c in "\"'":
            if c == "'" and i > 0 and text[i - 1].isalnum():  # a digit separator (1'000)
                out.append(" ")
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + " " * (j - i - 1) + c)
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def function_name(statement):
    """The name before the statement's first top-level parameter list ('' when there is none)."""
    depth = 0
    for k, ch in enumerate(statement):
        if ch == "<":
            depth += 1
        elif ch == ">" and depth > 0:
            depth -= 1
        elif ch == "(" and depth == 0:
            m = re.search(r"([~\w:]+(?:operator\s*\S+?)?)\s*$", statement[:k])
            return m.group(1) if m else ""
    return ""


def opens_function(statement):
    """Whether a brace after `statement` (at namespace or class level) opens a function body."""
    s = statement.strip()
    if not s or "(" not in s or ")" not in s or CONTAINER.match(s):
        return False
    before_paren = s[: s.index("(")]
    if "=" in before_paren.replace("operator=", "").replace("==", ""):
        return False  # an initialiser: `T x = f(...) {`, `auto f = [](...) {`
    tail = s[s.rindex(")") + 1:].split()
    if not tail:
        return True
    if "->" in s[s.rindex(")"):]:
        return True  # a trailing return type
    return all(t in FUNCTION_QUALIFIERS or t.startswith("noexcept") for t in tail)


def functions(text):
    """(name, first line, last line) of every function body at namespace or class level."""
    code = strip(text)
    found = []
    containers = []  # True for a namespace / class brace, False for a skipped initialiser
    statement_start = 0
    i, n = 0, len(code)
    while i < n:
        c = code[i]
        if c in ";}":
            if c == "}" and containers:
                containers.pop()
            statement_start = i + 1
            i += 1
            continue
        if c != "{":
            i += 1
            continue
        statement = code[statement_start:i]
        # Braces inside a constructor's initialiser list (`: a_{x}, b_(y) {`) are not the body.
        tail = statement.rstrip()
        is_member_init = bool(re.search(r"\)\s*:\s*", statement)) and tail and (tail[-1].isalnum() or tail[-1] in "_>")
        if opens_function(statement) and not is_member_init:
            j = match(code, i)
            first = code.count("\n", 0, statement_start + len(statement) - len(statement.lstrip())) + 1
            found.append((function_name(statement), first, code.count("\n", 0, j) + 1))
            i = j + 1
            statement_start = i
            continue
        if CONTAINER.match(statement.strip()) and not is_member_init:
            containers.append(True)
            statement_start = i + 1
            i += 1
            continue
        i = match(code, i) + 1  # an initialiser or a brace-initialised member: skipped whole
    return found


def match(code, open_index):
    depth = 0
    for j in range(open_index, len(code)):
        if code[j] == "{":
            depth += 1
        elif code[j] == "}":
            depth -= 1
            if depth == 0:
                return j
    return len(code) - 1


def allowed(path, name):
    for prefix, fn, _why in ALLOWED:
        if path.startswith(prefix) and (fn == "*" or fn == name):
            return True
    return False


def scan(root, limit):
    long_ones = []
    for folder in FOLDERS:
        for dirpath, _dirs, files in os.walk(os.path.join(root, folder)):
            for f in sorted(files):
                if not f.endswith((".cc", ".h")):
                    continue
                path = os.path.join(dirpath, f)
                rel = os.path.relpath(path, root)
                with open(path, encoding="utf-8", errors="replace") as fh:
                    text = fh.read()
                for name, first, last in functions(text):
                    if last - first + 1 > limit:
                        long_ones.append((rel, name, first, last - first + 1))
    return sorted(long_ones)


def check(root, limit, out=sys.stdout):
    bad = 0
    for rel, name, line, length in scan(root, limit):
        ok = allowed(rel, name)
        bad += not ok
        print(f"{rel}:{line}: {name}: {length} lines{' (allowed)' if ok else ''}", file=out)
    if bad:
        print(f"{bad} function(s) over {limit} lines in {', '.join(FOLDERS)}: split them "
              "(or, for a table, add it to ALLOWED in scripts/long_functions.py with why)", file=out)
    return 1 if bad else 0


def self_test(limit):
    """A tree with a long function planted (and the shapes the scanner must not miscount) fails."""
    body = "\n".join(f"  x += {k};" for k in range(limit))
    files = {
        "master/planted.cc": "namespace pz {\nint Planted(int x) {\n" + body + "\n  return x;\n}\n}\n",
        "worker/short.h": (
            "struct S {\n  S() : a_{1}, b_(2) {}\n  int F() const { return a_; }\n  int a_, b_;\n};\n"
            "const char* kText = R\"(\n{\n)\";\n// }\nint G() { return '{'; }\n"),
        "service/table.cc": "const int kTable[] = {\n" + ",\n".join(str(k) for k in range(2 * limit)) + "\n};\n",
    }
    with tempfile.TemporaryDirectory() as root:
        for rel, text in files.items():
            os.makedirs(os.path.dirname(os.path.join(root, rel)), exist_ok=True)
            with open(os.path.join(root, rel), "w") as fh:
                fh.write(text)
        found = scan(root, limit)
        expected = [("master/planted.cc", "Planted", 2, limit + 3)]
        if found != expected:
            print(f"self-test: expected {expected}, found {found}")
            return 1
        with open(os.devnull, "w") as devnull:
            if check(root, limit, devnull) != 1:
                print("self-test: the planted long function did not fail the check")
                return 1
        short = [f for f in functions(files["worker/short.h"])]
        if [n for n, _, _ in short] != ["S", "F", "G"]:
            print(f"self-test: worker/short.h: expected functions S, F, G, found {short}")
            return 1
    print(f"self-test: a planted {limit + 3}-line function fails the check")
    return 0


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    p.add_argument("--limit", type=int, default=LIMIT)
    p.add_argument("--self-test", action="store_true")
    a = p.parse_args()
    if a.self_test:
        return self_test(a.limit)
    return check(os.path.abspath(a.root), a.limit)


if __name__ == "__main__":
    sys.exit(main())
