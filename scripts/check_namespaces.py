#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Fails when a source file's namespace does not follow its folder (issue 15; docs/architecture.md).

    scripts/check_namespaces.py [ROOT]     # ROOT: the repository (default: this script's parent folder)

The rule: code in FOLDER/SUB/... is in `rsu::FOLDER`, or deeper along its path (`rsu::FOLDER::SUB`), with
`lib/` left out of the path (lib/lidar/ouster: `rsu::lidar` or `rsu::lidar::ouster`). One exception:
lib/common, the vocabulary every layer speaks (time, angles, poses, counters), is `rsu` itself.
Checked: lib/ and the folders of the programs (daemon, edge, io, dds, sim, eval, tools, vehicle_client).
Tests, benchmarks and fuzz targets open the namespace of the code they exercise and are not checked.

What is checked in a file: the namespace that holds its declarations. Namespaces opened at file scope
are followed inward while they hold nothing but other namespaces (`namespace rsu { namespace lidar {`);
the first one that holds code must be allowed. Namespaces inside it (`detail`, anonymous ones) are the
file's own business, as are anonymous namespaces at file scope (a program's local helpers), aliases
(`namespace po = ...`) and blocks of forward declarations only (`namespace rsu::io { class YamlField; }`).
Prints each violation as FILE:LINE: what, and exits 1 if there is one. Run by ctest (check_namespaces).
"""
import re
import sys

from check_sizes import SOURCE_SUFFIXES, blank_comments_and_literals, run_check

CHECKED_FOLDERS = ["lib", "daemon", "edge", "io", "dds", "sim", "eval", "tools", "vehicle_client"]
VOCABULARY_FOLDER = ("lib", "common")  # namespace rsu itself
NAMESPACE_HEAD = re.compile(r"\bnamespace\s*([\w:]*)\s*$")
FORWARD_DECLARATIONS_ONLY = re.compile(r"^\s*((class|struct|union|enum\s+class|enum)\s+\w+\s*;\s*)*$")


def allowed_namespaces(rel):
    """The namespaces code in the file at `rel` (relative to the root) may be in."""
    folders = list(rel.parent.parts)
    if tuple(folders[:2]) == VOCABULARY_FOLDER:
        return {"rsu"}
    if folders and folders[0] == "lib":
        folders = folders[1:]
    return {"::".join(["rsu"] + folders[:depth]) for depth in range(1, len(folders) + 1)}


def namespace_blocks(code):
    """The tree of namespace blocks reached from file scope through namespaces only: each a dict of
    name, line, body (the text directly inside it, nested namespace blocks left out) and children."""
    root = {"name": "", "line": 0, "body": [], "children": []}
    stack = [root]  # per open brace: its namespace block, or None for any other brace
    head_start = 0  # index just after the previous ';', '{' or '}'
    for i, c in enumerate(code):
        if c not in ";{}":
            continue
        head = code[head_start:i]
        top = stack[-1]
        match = NAMESPACE_HEAD.search(head) if c == "{" else None
        if match and top is not None:
            top["body"].append(head[: match.start()])
            block = {"name": match.group(1), "line": code.count("\n", 0, i) + 1, "body": [], "children": []}
            top["children"].append(block)
            stack.append(block)
        else:
            if top is not None:
                top["body"].append(head + (c if c != "}" else ""))
            if c == "{":
                stack.append(None)
            elif c == "}" and len(stack) > 1:
                stack.pop()
        head_start = i + 1
    return root


def declaring_namespaces(block, prefix):
    """(full name, line) of each namespace that holds the file's declarations (module comment)."""
    for child in block["children"]:
        if not child["name"]:
            continue  # anonymous at file scope (or inside namespaces that hold nothing else): local
        full = f"{prefix}::{child['name']}" if prefix else child["name"]
        body = "".join(child["body"])
        if body.strip() and not FORWARD_DECLARATIONS_ONLY.match(body):
            yield full, child["line"]
        elif not body.strip():
            yield from declaring_namespaces(child, full)


def check(root):
    problems = []
    for folder in CHECKED_FOLDERS:
        for path in sorted((root / folder).rglob("*")):
            if path.suffix not in SOURCE_SUFFIXES or not path.is_file():
                continue
            rel = path.relative_to(root)
            allowed = allowed_namespaces(rel)
            code = blank_comments_and_literals(path.read_text(encoding="utf-8", errors="replace"))
            code = re.sub(r"^[ \t]*#.*$", "", code, flags=re.M)  # preprocessor lines hold no braces we count
            for name, line in declaring_namespaces(namespace_blocks(code), ""):
                if name not in allowed:
                    problems.append(f"{rel}:{line}: namespace {name} (folder {rel.parent}: "
                                    f"{' or '.join(sorted(allowed))})")
    return problems


def main():
    return run_check("check_namespaces", check, "namespaces not following their folders")


if __name__ == "__main__":
    sys.exit(main())
