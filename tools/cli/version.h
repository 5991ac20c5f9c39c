// SPDX-License-Identifier: Apache-2.0
// --version for every program (one convention across the command-line tools): prints "<program>
// <project version>" and the program exits 0. Looked for before the options are parsed, so that it works
// without the options a program otherwise requires (and under each rsu-sim subcommand).
#pragma once

#include <cstdio>
#include <string_view>

namespace rsu::tools::cli {

inline constexpr const char* kVersionHelp = "print the version and exit";

// True (after printing) when the command line asks for the version.
inline bool print_version_if_asked(int argc, char** argv, const char* program) {
  for (int i = 1; i < argc; ++i) {
    if (std::string_view(argv[i]) == "--version") {
      std::printf("%s %s\n", program, RSU_VERSION);
      return true;
    }
  }
  return false;
}

}  // namespace rsu::tools::cli
