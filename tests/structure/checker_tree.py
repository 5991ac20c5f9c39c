# SPDX-License-Identifier: Apache-2.0
"""What the structure checkers' tests share: running a checker on a tree the test writes."""
import pathlib
import subprocess
import sys
import tempfile


def run_on_tree(checker, files):
    """(exit code, stdout) of `checker ROOT`, ROOT a fresh folder holding `files` ({path: text}, paths
    relative to ROOT) and a lib/ folder."""
    with tempfile.TemporaryDirectory() as root:
        (pathlib.Path(root) / "lib").mkdir()
        for name, text in files.items():
            path = pathlib.Path(root) / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text)
        done = subprocess.run([sys.executable, checker, root], capture_output=True, text=True)
        return done.returncode, done.stdout


class Expectations:
    """Collects what a test expected and did not find; `exit_code()` prints each and says whether any."""

    def __init__(self):
        self.failures = []

    def expect(self, what, condition):
        if not condition:
            self.failures.append(what)

    def exit_code(self):
        for f in self.failures:
            print("FAILED:", f)
        return 1 if self.failures else 0
