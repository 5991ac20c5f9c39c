#include "io/yaml_field.h"

#include <fstream>

namespace rsu::io {

YAML::Node parse_yaml(const std::string& text, const std::string& source_name) {
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw YamlError(source_name + ":" + std::to_string(e.mark.line + 1) + ": <syntax>: " + e.msg);
  }
}

std::string read_text_file(const std::string& path) {
  std::ifstream in(path);
  if (!in)
    throw YamlError(path + ":0: <file>: cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace rsu::io
