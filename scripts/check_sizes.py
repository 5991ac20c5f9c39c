#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Fails when a file in lib/ is over 450 lines or a function there over 80 (issue 15: lib/ stays readable).

    scripts/check_sizes.py [ROOT]     # ROOT: the repository (default: this script's parent folder)

Prints each violation as FILE:LINE: what, and exits 1 if there is one. Run by ctest (check_sizes).

How functions are found (a brace-depth heuristic, not a C++ parser): comments, string and character
literals are blanked first; then every '{' is classified by the text since the previous ';', '{' or '}'
(its head). A head starting a namespace, class, struct, union or enum opens a scope that may hold
functions; any other head that contains ')' and is not inside a function opens a function (free,
member, constructor with its initialiser list, defined in a class or not). Braces inside a function
(blocks, lambdas, initialisers) belong to it. A function's length is counted from the first line of its
head (the signature) to its closing brace, both included. Macros that hide braces or parentheses would
fool it; lib/ has none.
"""
import pathlib
import re
import sys

MAX_FILE_LINES = 450
MAX_FUNCTION_LINES = 80
SOURCE_SUFFIXES = {".h", ".hpp", ".cpp", ".cc"}
SCOPE_HEAD = re.compile(r"\b(namespace|class|struct|union|enum)\b")
ENDS_LIKE_SIGNATURE = re.compile(r"\)\s*(const|noexcept|override|final|\s)*$")


def blank_comments_and_literals(text):
    """The text with comments and literals replaced by spaces, newlines kept (line numbers stay)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
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
        elif c == 'R' and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == '_')):
            open_paren = text.find("(", i + 2)
            delimiter = text[i + 2:open_paren]
            j = text.find(")" + delimiter + '"', open_paren)
            j = n if j < 0 else j + len(delimiter) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            # A digit separator (1'000) is not a character literal.
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and text[i + 1].isalnum():
                out.append(c)
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(c + " " * (j - i - 2) + c if j - i >= 2 else " " * (j - i))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(text):
    """(first line, last line, name) of every function defined in `text` (module comment)."""
    code = blank_comments_and_literals(text)
    found = []
    stack = []  # per open brace: "scope", "function" or "inner"
    head_start = 0  # index just after the previous ';', '{' or '}'
    starts = []  # for each "function" entry on the stack: (first line, name)
    for i, c in enumerate(code):
        if c == ";":
            head_start = i + 1
        elif c == "{":
            head = code[head_start:i]
            if "function" in stack:
                kind = "inner"
            elif SCOPE_HEAD.search(head) and not ENDS_LIKE_SIGNATURE.search(head):
                kind = "scope"  # (a template's "class T" does not make a function a scope)
            elif ")" in head:
                kind = "function"
            else:
                kind = "inner"
            if kind == "function":
                first = head_start + (len(head) - len(head.lstrip()))
                name = re.findall(r"([~\w:]+(?:operator\s*\S+?)?)\s*\(", head)
                starts.append((code.count("\n", 0, first) + 1, name[0] if name else "?"))
            stack.append(kind)
            head_start = i + 1
        elif c == "}":
            if stack:
                kind = stack.pop()
                if kind == "function":
                    first_line, name = starts.pop()
                    found.append((first_line, code.count("\n", 0, i) + 1, name))
            head_start = i + 1
    return found


def check(root):
    problems = []
    for path in sorted((root / "lib").rglob("*")):
        if path.suffix not in SOURCE_SUFFIXES or not path.is_file():
            continue
        text = path.read_text(encoding="utf-8", errors="replace")
        rel = path.relative_to(root)
        lines = text.count("\n") + (0 if text.endswith("\n") or not text else 1)
        if lines > MAX_FILE_LINES:
            problems.append(f"{rel}:1: {lines} lines (limit {MAX_FILE_LINES})")
        for first, last, name in functions(text):
            length = last - first + 1
            if length > MAX_FUNCTION_LINES:
                problems.append(f"{rel}:{first}: function {name} is {length} lines (limit {MAX_FUNCTION_LINES})")
    return problems


def run_check(name, check, what_fails):
    """The command line of a structure check: ROOT from argv (default: this script's parent folder),
    each problem `check(root)` returns printed, exit 1 if there is one with `what_fails` on stderr."""
    root = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent
    if not (root / "lib").is_dir():
        print(f"{name}: {root}/lib: no such folder", file=sys.stderr)
        return 2
    problems = check(root)
    for p in problems:
        print(p)
    if problems:
        print(f"{name}: {len(problems)} {what_fails}", file=sys.stderr)
        return 1
    return 0


def main():
    return run_check("check_sizes", check,
                     f"over the limits (files {MAX_FILE_LINES} lines, functions {MAX_FUNCTION_LINES})")


if __name__ == "__main__":
    sys.exit(main())
