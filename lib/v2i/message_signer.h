// SPDX-License-Identifier: Apache-2.0
// The sending side of V2I message security: encodes messages with the header every signed message
// carries (generation time = now, the signer's own sequence number) and signs them with the sender's
// key (proto/v2i.proto). Without a key (insecure mode, local development only) it sends unsigned.
// Pure: `now` is passed in.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "common/time.h"
#include "v2i/messages.h"
#include "v2i/security/ed25519.h"
#include "v2i/wire_codec.h"

namespace rsu::v2i {

class MessageSigner {
 public:
  // `first_sequence`: where the signer's counter starts (0 after a start; receivers accept a restart).
  explicit MessageSigner(std::optional<security::SigningKey> key, std::uint32_t first_sequence = 0)
      : key_(std::move(key)), next_sequence_(first_sequence) {}

  // Each call uses the next sequence number (wrapping modulo 2^32). Empty on failure (too large).
  std::vector<std::uint8_t> encode(const VehicleAnnouncement& m, TimeNs now) { return seal(m, now); }
  std::vector<std::uint8_t> encode(const Correction& m, TimeNs now) { return seal(m, now); }
  std::vector<std::uint8_t> encode(const RsuAdvertisement& m, TimeNs now) { return seal(m, now); }
  std::vector<std::uint8_t> encode(const AnnouncementRefusal& m, TimeNs now) { return seal(m, now); }
  std::vector<std::uint8_t> encode(const FixWithheld& m, TimeNs now) { return seal(m, now); }

  bool signs() const { return key_.has_value(); }
  const security::SigningKey* key() const { return key_ ? &*key_ : nullptr; }
  std::uint32_t next_sequence() const { return next_sequence_; }

 private:
  template <typename Body>
  std::vector<std::uint8_t> seal(const Body& body, TimeNs now) {
    const MessageHeader header{now, next_sequence_++};
    return encode_v2i_message(body, header, key());
  }

  std::optional<security::SigningKey> key_;
  std::uint32_t next_sequence_ = 0;
};

}  // namespace rsu::v2i
