// SPDX-License-Identifier: Apache-2.0
#include "io/text_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

namespace rsu::io {

std::string errno_text() {
  return std::strerror(errno);
}

std::string read_whole_file(const std::string& path) {
  struct Closer {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  const std::unique_ptr<std::FILE, Closer> file(std::fopen(path.c_str(), "rb"));
  if (!file)
    throw FileError(path, "cannot open: " + errno_text());
  std::string text;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, file.get())) > 0)
    text.append(buffer, n);
  if (std::ferror(file.get()))
    throw FileError(path, "cannot read: " + errno_text());
  return text;
}

void write_file_atomically(const std::string& path, std::string_view text, unsigned mode) {
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0)
    throw FileError(tmp, "cannot open: " + errno_text());
  bool ok = ::fchmod(fd, static_cast<mode_t>(mode)) == 0;
  std::string problem = ok ? "" : "cannot set its mode: " + errno_text();
  for (std::size_t done = 0; ok && done < text.size();) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0) {
      ok = false;
      problem = "cannot write: " + errno_text();
      break;
    }
    done += static_cast<std::size_t>(n);
  }
  ::close(fd);
  if (ok && ::rename(tmp.c_str(), path.c_str()) != 0) {
    ok = false;
    problem = "cannot rename to " + path + ": " + errno_text();
  }
  if (!ok) {
    ::unlink(tmp.c_str());
    throw FileError(tmp, problem);
  }
}

}  // namespace rsu::io
