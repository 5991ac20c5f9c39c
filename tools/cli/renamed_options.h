// SPDX-License-Identifier: Apache-2.0
// Options renamed to carry their unit (--length -> --length-m): the old spelling stays accepted for
// existing scripts, with a warning, by rewriting the command line before it is parsed, so that each
// program declares, and its --help shows, only the new name.
#pragma once

#include <cstdio>
#include <deque>
#include <initializer_list>
#include <string>
#include <string_view>

namespace rsu::tools::cli {

struct RenamedOption {
  std::string_view old_name;  // without the leading "--"
  std::string_view new_name;
};

// Replaces "--old" and "--old=VALUE" in argv by the new name (up to a "--"), warning once per use.
inline void accept_renamed_options(int argc, char** argv, std::initializer_list<RenamedOption> renames,
                                   const char* program) {
  static std::deque<std::string> rewritten;  // argv points into it for the rest of the run
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg(argv[i]);
    if (arg == "--")
      break;
    if (!arg.starts_with("--"))
      continue;
    const std::size_t equals = arg.find('=');
    const std::string_view name = arg.substr(2, equals == std::string_view::npos ? equals : equals - 2);
    for (const RenamedOption& r : renames) {
      if (name != r.old_name)
        continue;
      std::fprintf(stderr, "%s: --%.*s is deprecated, use --%.*s\n", program, static_cast<int>(name.size()),
                   name.data(), static_cast<int>(r.new_name.size()), r.new_name.data());
      rewritten.push_back("--" + std::string(r.new_name) + std::string(arg.substr(2 + name.size())));
      argv[i] = rewritten.back().data();
      break;
    }
  }
}

}  // namespace rsu::tools::cli
