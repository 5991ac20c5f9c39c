// Reading a whole (small) text file, and the words for why a file could not be opened: every program's
// file errors name the file and the operating system's reason (strerror of errno: "Permission denied",
// "No such file or directory"), since "cannot open" alone sends an operator guessing.
#pragma once

#include <stdexcept>
#include <string>

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

}  // namespace rsu::io
