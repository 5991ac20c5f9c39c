#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""scripts/check_namespaces.py on trees this test writes: silent where each file's namespace follows its
folder (also nested spellings, deeper along the path, lib/common as rsu, local anonymous namespaces,
aliases, forward declarations of another folder's types, namespaces in comments and strings), and naming
each file whose namespace does not."""
import sys

from checker_tree import Expectations
from checker_tree import run_on_tree as run


def main():
    checker = sys.argv[1]
    expectations = Expectations()
    expect = expectations.expect

    following = {
        "lib/common/time.h": "namespace rsu {\nusing TimeNs = long;\n}\n",
        "lib/lidar/point.h": "namespace rsu::lidar {\nstruct P {\n  int x;\n};\nnamespace detail {\nint f();\n}\n}\n",
        "lib/lidar/ouster/a.h": "namespace rsu::lidar::ouster {\nstruct D {};\n}\n",
        "lib/lidar/ouster/b.cpp": "namespace rsu::lidar {\nint g() { return 1; }\n}\n",
        "lib/v2i/nested.h": "namespace rsu {\nnamespace v2i {\nstruct M {};\n}  // namespace v2i\n}\n",
        "dds/qos.h": "namespace rsu::io {\nclass YamlField;\n}\nnamespace rsu::dds {\nstruct Q {};\n}\n",
        "tools/x/main.cpp": ("#include <x>\nnamespace po = boost::program_options;\nusing namespace rsu;\n"
                             "namespace {\nint h() { return 0; }\n}\nint main() { return h(); }\n"),
        "io/pcd.cpp": ("// namespace rsu::wrong {\nnamespace rsu::io {\nconst char* s = \"namespace rsu::x {\";\n"
                       "}\n"),
    }
    rc, out = run(checker, following)
    expect(f"namespaces following their folders pass (rc {rc}, {out!r})", rc == 0 and out == "")

    not_following = {
        "lib/lidar/flat.h": "namespace rsu {\nstruct P {};\n}\n",
        "lib/common/angles.h": "namespace rsu::common {\nconstexpr double kPi = 3.14;\n}\n",
        "io/reader.cpp": "#include \"a.h\"\n\nnamespace rsu::dds {\nint r();\n}\n",
        "lib/core/nested.h": "namespace rsu {\nnamespace rsu_core {\nclass C {};\n}\n}\n",
        "tools/cli/version.h": "namespace rsu::cli {\nint v();\n}\n",
    }
    rc, out = run(checker, not_following)
    expect(f"namespaces not following their folders fail (rc {rc})", rc == 1)
    for needle in ["lib/lidar/flat.h:1: namespace rsu (folder lib/lidar: rsu::lidar)",
                   "lib/common/angles.h:1: namespace rsu::common (folder lib/common: rsu)",
                   "io/reader.cpp:3: namespace rsu::dds (folder io: rsu::io)",
                   "lib/core/nested.h:2: namespace rsu::rsu_core (folder lib/core: rsu::core)",
                   "tools/cli/version.h:1: namespace rsu::cli (folder tools/cli: rsu::tools or rsu::tools::cli)"]:
        expect(f"names {needle!r} in {out!r}", needle in out)
    expect(f"names five files in {out!r}", out.count("\n") == 5)
    return expectations.exit_code()


if __name__ == "__main__":
    sys.exit(main())
