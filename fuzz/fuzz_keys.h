// SPDX-License-Identifier: Apache-2.0
// The fixed keys of the fuzz harnesses and their seed corpora (fuzz/make_seed_corpus.cpp): the seeds
// are signed with them, so that a harness in signed mode reaches past the signature check on seeds
// and on mutations that keep the signed payload intact. Test keys only; never deployed.
#pragma once

#include "v2i/security/ed25519.h"
#include "v2i/security/trust_list.h"

namespace rsu::fuzz {

inline v2i::security::SigningKey fuzz_key(std::uint8_t fill) {
  v2i::security::Seed seed{};
  seed.fill(fill);
  return v2i::security::SigningKey(seed);
}

inline v2i::security::SigningKey fuzz_vehicle_key() {
  return fuzz_key(0x5A);
}
inline v2i::security::SigningKey fuzz_rsu_key() {
  return fuzz_key(0xA5);
}

// The vehicle key may announce for the seeds' vehicles 7, 8 and 9; the RSU key speaks for RSU 3.
inline v2i::security::TrustList fuzz_trust_list() {
  v2i::security::TrustList list;
  list.add({fuzz_vehicle_key().public_key(), v2i::security::SignerRole::kVehicle, {7, 8, 9}});
  list.add({fuzz_rsu_key().public_key(), v2i::security::SignerRole::kRsu, {3}});
  return list;
}

}  // namespace rsu::fuzz
