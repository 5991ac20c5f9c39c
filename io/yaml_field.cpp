#include "io/yaml_field.h"

#include <fstream>

namespace rsu::io {

std::string read_text_file(const std::string& path) {
  std::ifstream in(path);
  if (!in)
    throw YamlError(path + ":0: <file>: cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace rsu::io
