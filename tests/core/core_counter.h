// SPDX-License-Identifier: Apache-2.0
// One of RsuCore::counters() by name, for the tests of the core.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "core/rsu_core.h"

namespace rsu::core::testing {

// The counter `name` (fails the test if there is none).
inline std::uint64_t counter(const RsuCore& core, const std::string& name) {
  for (const auto& [n, v] : core.counters()) {
    if (n == name)
      return v;
  }
  ADD_FAILURE() << "no counter " << name;
  return 0;
}

}  // namespace rsu::core::testing
