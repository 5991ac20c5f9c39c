// SPDX-License-Identifier: Apache-2.0
// Fuzzes PCD reading (io/pcd_io.h, the project's own reader): any file must give points or a PcdError.
// read_pcd takes a path, so each input is written to a temporary file first.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "io/pcd_io.h"

namespace {

std::string temp_path() {
  return "/tmp/rsu_pcd_fuzzer_" + std::to_string(::getpid()) + ".pcd";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = temp_path();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr)
    std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size)
    std::abort();
  std::fclose(f);
  try {
    (void)rsu::io::read_pcd(path);
  } catch (const rsu::io::PcdError&) {
    // the documented failure
  }
  std::remove(path.c_str());
  return 0;
}
