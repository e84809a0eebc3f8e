#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Library source files over a line budget and functions over a length budget (docs/developing.md:
"no library source file over ~800 lines, no function over ~150 lines").

    tools/code_sizes.py [--file-lines 800] [--function-lines 150] [--check] DIR...

Functions are found at top level by brace matching (comments and strings skipped); the length is
from the line of the name to the closing brace. --check exits 1 when anything is over budget.
"""
import argparse
import pathlib
import re
import sys

NAME = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)\s*\($")


def strip(text):
    """Comments, strings and character literals blanked, newlines kept."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + " " * (j - i - 1) + c)
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(path):
    text = strip(path.read_text(errors="replace"))
    depth, start, name = 0, None, None
    for m in re.finditer(r"[{}]", text):
        if m.group() == "{":
            if depth == 0:
                head = text[:m.start()].rstrip()
                # a function body: the text before the brace ends with ')' (parameter list)
                if head.endswith(")"):
                    k, level = len(head) - 1, 0
                    while k >= 0:
                        level += {")": 1, "(": -1}.get(head[k], 0)
                        if level == 0:
                            break
                        k -= 1
                    nm = NAME.search(head[:k + 1])
                    if nm and nm.group(1) not in ("if", "for", "while", "switch"):
                        name = nm.group(1)
                        start = head.count("\n", 0, nm.start()) + 1
            depth += 1
        else:
            depth -= 1
            if depth == 0 and name:
                yield name, start, text.count("\n", 0, m.start()) + 1
                name = None


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--file-lines", type=int, default=800)
    ap.add_argument("--function-lines", type=int, default=150)
    ap.add_argument("--check", action="store_true")
    a = ap.parse_args()
    over = 0
    for d in a.dirs:
        for p in sorted(pathlib.Path(d).rglob("*.c")):
            lines = p.read_text(errors="replace").count("\n")
            if lines > a.file_lines:
                print(f"{p}: {lines} lines (file budget {a.file_lines})")
                over += 1
            for name, l0, l1 in functions(p):
                if l1 - l0 + 1 > a.function_lines:
                    print(f"{p}:{l0}: {name}: {l1 - l0 + 1} lines (function budget {a.function_lines})")
                    over += 1
    print(f"{over} over budget")
    return 1 if a.check and over else 0


if __name__ == "__main__":
    sys.exit(main())
