// SPDX-License-Identifier: Apache-2.0
// Fuzzes the scenario file parser (sim/scenario.h): any text must give a scenario or a ScenarioError
// naming the line and field, never a crash or another exception.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sim/scenario.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    (void)rsu::sim::parse_scenario(text, "scenarios/fuzz.yaml");
  } catch (const rsu::sim::ScenarioError&) {
    // the documented failure
  }
  return 0;
}
