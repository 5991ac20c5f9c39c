#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Every configuration key rsud accepts is documented in the shipped deploy/rsud.yaml (issue 14 item 5).

The keys are learned from rsud itself, not from its source: rsud refuses an unknown key naming every key
it accepts there ("<path>.zzz_probe: unknown field (expected one of: a, b, c)"), so the test puts a probe
key into each section of the shipped file, reads the accepted keys from rsud --check-config's error, and
descends into every key that is itself a section (present in the shipped file or, when commented out
there, found by probing it alone). Each accepted key must appear in the shipped file as `key:`, set or in
a comment. Usage: config_keys_documented.py RSUD SHIPPED_CONFIG WORK_DIR
"""
import copy
import os
import re
import subprocess
import sys

try:
    import yaml
except ImportError:
    print("SKIP: PyYAML is not installed (apt-get install python3-yaml)")
    sys.exit(77)

PROBE = "zzz_probe"


def accepted_keys(rsud, config, path, work):
    """The keys rsud accepts in the section at `path` (a list of keys) of `config`, or None when the
    probe did not reach that section's key check."""
    probed = copy.deepcopy(config)
    node = probed
    for key in path:
        node = node[key]
    node[PROBE] = 1
    file = os.path.join(work, "probe.yaml")
    with open(file, "w") as f:
        yaml.safe_dump(probed, f, sort_keys=False)
    r = subprocess.run([rsud, "--check-config", "--config", file], capture_output=True, text=True, timeout=30)
    where = ".".join(path + [PROBE])
    m = re.search(r"(?:^|: )%s: unknown field \(expected one of: ([^)]*)\)" % re.escape(where), r.stdout + r.stderr,
                  re.M)
    return [k.strip() for k in m.group(1).split(",")] if m else None


def main():
    rsud, shipped_path, work = sys.argv[1:4]
    os.makedirs(work, exist_ok=True)
    with open(shipped_path) as f:
        text = f.read()
    shipped = yaml.safe_load(text)
    documented = lambda key: re.search(r"(^|[\s{#,(])%s:" % re.escape(key), text, re.M) is not None  # noqa: E731

    sections, undocumented, unreached = 0, [], []
    todo = [(shipped, [])]
    while todo:
        config, path = todo.pop()
        keys = accepted_keys(rsud, config, path, work)
        if keys is None:
            unreached.append(".".join(path))
            continue
        sections += 1
        node = config
        for key in path:
            node = node[key]
        for key in keys:
            if not documented(key):
                undocumented.append(".".join(path + [key]))
            if isinstance(node.get(key), dict):
                todo.append((config, path + [key]))
            elif key not in node:
                # Commented out in the shipped file: is it a section? Probe it alone in its parent (an
                # input section excludes its siblings).
                alone = copy.deepcopy(config)
                parent = alone
                for k in path:
                    parent = parent[k]
                parent.clear()
                parent[key] = {}
                if accepted_keys(rsud, alone, path + [key], work) is not None:
                    todo.append((alone, path + [key]))
    assert sections >= 10, "only %d sections reached: does rsud still name the keys it accepts?" % sections
    if unreached:
        print("note: sections whose keys could not be probed: %s" % ", ".join(unreached))
    if undocumented:
        print("FAIL: keys rsud accepts that deploy/rsud.yaml does not mention: %s" % ", ".join(undocumented))
        return 1
    print("OK: every key of %d sections rsud accepts is in %s" % (sections, shipped_path))
    return 0


if __name__ == "__main__":
    sys.exit(main())
