#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Every source file of the project carries the licence line `SPDX-License-Identifier: Apache-2.0`
(LICENSE) as its first line (after a #! line): C, C++, .proto and .idl with //; Python, shell, CMake
(also its .cmake.in and .pc.in templates) and any other file that starts with #! (.ci/run, the Debian
maintainer scripts) with #. Usage: spdx_headers.py [--check] [REPOSITORY] - without --check the line is added where missing;
with --check the files without it are listed and the exit code is 1 (ctest license_spdx_headers).
Only files git tracks are looked at (third-party data under tests/data carries no code)."""
import os
import subprocess
import sys

TAG = "SPDX-License-Identifier: Apache-2.0"
SLASHES = (".cpp", ".h", ".c", ".proto", ".idl")
HASHES = (".py", ".sh", ".cmake", ".cmake.in", ".pc.in")


def comment_for(path):
    name = os.path.basename(path)
    if name.endswith(SLASHES):
        return "// "
    if name.endswith(HASHES) or name == "CMakeLists.txt":
        return "# "
    with open(path, "rb") as f:
        return "# " if f.read(2) == b"#!" else None


def main():
    args = [a for a in sys.argv[1:] if a != "--check"]
    check = "--check" in sys.argv[1:]
    root = args[0] if args else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    listed = subprocess.run(["git", "-C", root, "ls-files"], capture_output=True, text=True)
    if listed.returncode != 0:
        print("SKIP: %s is not a git checkout (the files are found with git ls-files)" % root)
        return 77
    files = listed.stdout.split()
    missing = []
    looked_at = 0
    for rel in files:
        path = os.path.join(root, rel)
        if not os.path.isfile(path) or os.path.islink(path):
            continue
        comment = comment_for(path)
        if comment is None:
            continue
        looked_at += 1
        with open(path, encoding="utf-8") as f:
            lines = f.read().split("\n")
        at = 1 if lines and lines[0].startswith("#!") else 0
        if len(lines) > at and TAG in lines[at]:
            continue
        missing.append(rel)
        if not check:
            lines.insert(at, comment + TAG)
            with open(path, "w", encoding="utf-8") as f:
                f.write("\n".join(lines))
    if check and missing:
        print("%d file(s) without the line \"%s\" (run scripts/spdx_headers.py):" % (len(missing), TAG))
        print("\n".join(missing))
        return 1
    print("%s: %d source file(s), %d given the line now" % (TAG, looked_at, len(missing)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
