// SPDX-License-Identifier: Apache-2.0
// Reading a whole (small) text file, and the words for why a file could not be opened: every program's
// file errors name the file and the operating system's reason (strerror of errno: "Permission denied",
// "No such file or directory"), since "cannot open" alone sends an operator guessing.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace rsu::io {

// what(): "<path>: <problem>"; problem(): "cannot open: Permission denied" alone, for callers that
// place the path themselves ("<path>:0: <file>: cannot open: ..." in located YAML errors).
class FileError : public std::runtime_error {
 public:
  FileError(const std::string& path, const std::string& problem)
      : std::runtime_error(path + ": " + problem), problem_(problem) {}
  const std::string& problem() const { return problem_; }

 private:
  std::string problem_;
};

// The text of errno now ("Permission denied"); call it right after the failing call.
std::string errno_text();

// The whole file. Throws FileError "<path>: cannot open: <reason>" (or "cannot read: <reason>").
std::string read_whole_file(const std::string& path);

// Replaces `path` with `text` atomically: written to "<path>.tmp" with permissions `mode` (whatever the
// umask), then renamed over it, so that a reader sees the old file or the new one, never a part.
// Throws FileError "<path>.tmp: cannot open: <reason>" (or write, rename).
void write_file_atomically(const std::string& path, std::string_view text, unsigned mode);

}  // namespace rsu::io
