#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""scripts/check_sizes.py on trees this test writes: silent on code within the limits, and naming each
function over 80 lines (free, member defined in a class, constructor with an initialiser list, template
with "class T") and each file over 450 lines, whatever braces comments and strings hold."""
import sys

from checker_tree import Expectations, run_on_tree


def body(lines):
    return "".join(f"  x += {i};\n" for i in range(lines))


def run(checker, files):
    return run_on_tree(checker, {f"lib/{name}": text for name, text in files.items()})


def main():
    checker = sys.argv[1]
    expectations = Expectations()
    expect = expectations.expect

    # 78 body lines + signature + closing brace = 80 lines: within the limit. Braces in comments and
    # strings must not count.
    ok_code = ("namespace a {\nint f(int x) {\n" + body(78) + "}\n}  // namespace a\n"
               "// a comment with { an open brace\nconst char* s = \"{\";\n")
    rc, out = run(checker, {"a/ok.cpp": ok_code})
    expect(f"code within the limits passes (rc {rc}, {out!r})", rc == 0 and out == "")

    long_code = {
        "b/free.cpp": "namespace b {\nint g(int x) {\n" + body(79) + "  return x;\n}\n}\n",
        "b/member.h": "struct S {\n  int h(int x) const {\n" + body(80) + "  }\n};\n",
        "b/ctor.cpp": "S::S(int a)\n    : a_(a),\n      b_(a) {\n  int x = 0;\n" + body(78) + "}\n",
        "b/templ.h": "template <class T>\nT k(T x) {\n  if (x) {\n" + body(79) + "  }\n  return x;\n}\n",
        "b/big.h": "// line\n" * 451,
    }
    rc, out = run(checker, long_code)
    expect(f"long code fails (rc {rc})", rc == 1)
    for needle in ["b/free.cpp:2: function g", "b/member.h:2: function h", "b/ctor.cpp:1: function S::S",
                   "b/templ.h:1: function k", "b/big.h:1: 451 lines"]:
        expect(f"names {needle!r} in {out!r}", needle in out)
    return expectations.exit_code()


if __name__ == "__main__":
    sys.exit(main())
