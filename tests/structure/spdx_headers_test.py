#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""scripts/spdx_headers.py on a git repository this test writes: --check names each source file without
the licence line (C++, Python, shell, CMake, an extensionless #! script) and none of the rest (a file with
the line after its #!, a text file, binary data, an untracked file); without --check it adds the line as
the first line, after a #! line, keeping the rest byte for byte; then --check passes."""
import os
import subprocess
import sys
import tempfile

TAG = "SPDX-License-Identifier: Apache-2.0"
FILES = {
    "lib/a.cpp": "#include <x>\nint f();\n",
    "tools/b.py": "#!/usr/bin/env python3\nprint(1)\n",
    "tests/c.sh": "#!/bin/sh\n# " + TAG + "\necho ok\n",
    "CMakeLists.txt": "project(x)\n",
    ".ci/run": "#!/usr/bin/env bash\nexit 0\n",
    "docs/notes.md": "# notes\n",
}


def run(checker, root, *args):
    out = subprocess.run([sys.executable, checker, *args, root], capture_output=True, text=True)
    return out.returncode, out.stdout


def main():
    checker = sys.argv[1]
    failures = []
    with tempfile.TemporaryDirectory() as root:
        for rel, text in FILES.items():
            os.makedirs(os.path.dirname(os.path.join(root, rel)) or root, exist_ok=True)
            with open(os.path.join(root, rel), "w") as f:
                f.write(text)
        with open(os.path.join(root, "data.bin"), "wb") as f:
            f.write(bytes(range(256)))
        subprocess.run(["git", "init", "-q", root], check=True)
        subprocess.run(["git", "-C", root, "add", "."], check=True)
        with open(os.path.join(root, "untracked.cpp"), "w") as f:
            f.write("int g();\n")
        rc, out = run(checker, root, "--check")
        missing = sorted(out.splitlines()[1:])
        if rc != 1 or missing != sorted(["lib/a.cpp", "tools/b.py", "CMakeLists.txt", ".ci/run"]):
            failures.append("--check: rc %d, listed %r" % (rc, missing))
        rc, out = run(checker, root)
        if rc != 0:
            failures.append("adding: rc %d %r" % (rc, out))
        expected = {
            "lib/a.cpp": "// " + TAG + "\n" + FILES["lib/a.cpp"],
            "tools/b.py": "#!/usr/bin/env python3\n# " + TAG + "\nprint(1)\n",
            "tests/c.sh": FILES["tests/c.sh"],
            "CMakeLists.txt": "# " + TAG + "\n" + FILES["CMakeLists.txt"],
            ".ci/run": "#!/usr/bin/env bash\n# " + TAG + "\nexit 0\n",
            "docs/notes.md": FILES["docs/notes.md"],
            "untracked.cpp": "int g();\n",
        }
        for rel, text in expected.items():
            with open(os.path.join(root, rel)) as f:
                got = f.read()
            if got != text:
                failures.append("%s is %r, expected %r" % (rel, got, text))
        rc, out = run(checker, root, "--check")
        if rc != 0:
            failures.append("--check after adding: rc %d %r" % (rc, out))
    for f in failures:
        print("FAIL: " + f)
    print("OK" if not failures else "%d failure(s)" % len(failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
