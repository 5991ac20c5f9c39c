// SPDX-License-Identifier: Apache-2.0
#include "io/yaml_field.h"

#include "io/text_file.h"

namespace rsu::io {

std::string read_text_file(const std::string& path) {
  try {
    return read_whole_file(path);
  } catch (const FileError& e) {
    throw YamlError(path + ":0: <file>: " + e.problem());
  }
}

}  // namespace rsu::io
