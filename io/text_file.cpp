#include "io/text_file.h"

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

}  // namespace rsu::io
