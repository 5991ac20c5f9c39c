// SPDX-License-Identifier: Apache-2.0
// The trust list: which public keys a receiver accepts signatures from, and what each may sign.
//
// Text format (one entry per line; '#' starts a comment; parsed from TEXT the caller read):
//     <role> <public key: 64 hex digits> <ids: comma-separated decimal, e.g. 7 or 7,8,12>
//     rsu      5a0b...e1  1
//     vehicle  c3d9...07  7,8
// role "rsu": the key may sign corrections and advertisements carrying one of these rsu_ids.
// role "vehicle": the key may sign announcements carrying one of these vehicle_ids.
// The ids are required: a key is bound to the ids it may speak for, so that one vehicle's key cannot
// announce (and so draw corrections) for another vehicle, and one RSU's key cannot pose as another
// RSU. A key appears at most once. Errors throw std::invalid_argument "<source>:<line>: ...".
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "v2i/security/ed25519.h"

namespace rsu::v2i::security {

enum class SignerRole : std::uint8_t { kRsu, kVehicle };

const char* to_string(SignerRole role);

struct TrustEntry {
  PublicKey public_key{};
  SignerRole role = SignerRole::kVehicle;
  std::vector<std::uint64_t> ids;  // rsu_ids (role rsu) or vehicle_ids (role vehicle); never empty

  bool may_sign_for(std::uint64_t id) const;
};

class TrustList {
 public:
  TrustList() { ensure_sodium_initialized(); }

  // Throws std::invalid_argument if the key is already listed or `ids` is empty.
  void add(const TrustEntry& entry);
  const TrustEntry* find(const KeyId& key_id) const;
  std::size_t size() const { return entries_.size(); }
  std::size_t count(SignerRole role) const;
  const std::map<KeyId, TrustEntry>& entries() const { return entries_; }

 private:
  std::map<KeyId, TrustEntry> entries_;
};

TrustList parse_trust_list_text(std::string_view text, std::string_view source);

// One line of the text format (with a comment naming the key id), for rsu-keygen.
std::string trust_entry_text(const TrustEntry& entry);

}  // namespace rsu::v2i::security
