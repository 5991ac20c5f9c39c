// SPDX-License-Identifier: Apache-2.0
// A signing key from a seed of one repeated byte: distinct, reproducible keys for the tests.
#pragma once

#include <cstdint>

#include "v2i/security/ed25519.h"

namespace rsu {

inline v2i::security::SigningKey key_from(std::uint8_t fill) {
  v2i::security::Seed seed{};
  seed.fill(fill);
  return v2i::security::SigningKey(seed);
}

}  // namespace rsu
