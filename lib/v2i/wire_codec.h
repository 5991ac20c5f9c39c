// SPDX-License-Identifier: Apache-2.0
// Encoding and decoding of V2I datagrams (proto/v2i.proto, version 2) to and from the plain structs of
// messages.h. A datagram is an envelope {protocol_version, payload bytes, signer key id, signature}
// around a payload {generation time, sequence, body}. Decoding here checks structure only (parses, the
// version is spoken, has a body, covariances have 9 values); signatures and replay are
// message_authenticator.h's job, field plausibility announcement_validation.h's. Never throws, whatever
// the bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "common/time.h"
#include "v2i/messages.h"
#include "v2i/security/ed25519.h"

namespace rsu::v2i {

// Largest datagram accepted or produced: an IPv6 minimum-MTU packet (1280) minus the IPv6 and UDP
// headers, so a message is never fragmented on any link. A signed announcement is about 250 bytes.
inline constexpr std::size_t kMaxDatagramBytes = 1232;

// The domain-separation prefix of the signed bytes: context || 0x00 || payload (proto/v2i.proto).
inline constexpr std::string_view kSigningContext = "rsu-v2i signed payload v2";

enum class DecodeStatus : std::uint8_t {
  kOk,
  kEmpty,
  kTooLarge,
  kParseError,           // the envelope or its payload is not protobuf of the expected message
  kUnsupportedVersion,   // protocol_version is not kProtocolVersion (a version 1 datagram, say)
  kNoBody,               // parsed, but none of the bodies this code knows in it (a newer sender's)
  kMalformedCovariance,  // a covariance without exactly 9 values
  kCount,
};

const char* to_string(DecodeStatus status);

// The signed header every payload carries (V2iPayload).
struct MessageHeader {
  TimeNs generation_time = 0;  // when the sender created and signed the message
  std::uint32_t sequence = 0;  // the signer's counter over everything it signs
};

// The outer message as received: the payload is kept as the exact bytes that were signed.
struct Envelope {
  std::uint32_t protocol_version = 0;
  std::string payload;
  std::string signer_key_id;  // 8 bytes when signed, empty when not
  std::string signature;      // 64 bytes when signed, empty when not
};

struct DecodedEnvelope {
  DecodeStatus status = DecodeStatus::kParseError;
  Envelope envelope;  // meaningful only when status is kOk
};

using MessageBody = std::variant<std::monostate, VehicleAnnouncement, Correction, RsuAdvertisement,
                                 AnnouncementRefusal, FixWithheld>;

struct DecodedMessage {
  DecodeStatus status = DecodeStatus::kParseError;
  MessageHeader header;
  MessageBody body;  // set only when status is kOk; carries the envelope's protocol_version
};

// Step 1: the envelope (size, protobuf, version). Step 2: its payload. In signed mode the authenticator
// reads the payload's time and sequence before verifying the signature (to refuse what its windows refuse
// without the costly check) and uses nothing else of it until the signature verified.
DecodedEnvelope decode_envelope(std::span<const std::uint8_t> bytes);
DecodedMessage decode_payload(const Envelope& envelope);
// Both steps, checking no signature (tests, fuzzing, tools that only look).
DecodedMessage decode_v2i_message(std::span<const std::uint8_t> bytes);

// The bytes an Ed25519 signature covers: kSigningContext, one zero byte, the payload bytes.
std::vector<std::uint8_t> signing_input(std::string_view payload);

// Serialise one message: the struct's protocol_version goes in the envelope, `header` in the payload,
// signed by `signer` (nullptr: unsigned, for insecure mode). Empty on failure, e.g. a result over
// kMaxDatagramBytes.
std::vector<std::uint8_t> encode_v2i_message(const VehicleAnnouncement& announcement,
                                             const MessageHeader& header, const security::SigningKey* signer);
std::vector<std::uint8_t> encode_v2i_message(const Correction& correction, const MessageHeader& header,
                                             const security::SigningKey* signer);
std::vector<std::uint8_t> encode_v2i_message(const RsuAdvertisement& advertisement,
                                             const MessageHeader& header, const security::SigningKey* signer);
std::vector<std::uint8_t> encode_v2i_message(const AnnouncementRefusal& refusal, const MessageHeader& header,
                                             const security::SigningKey* signer);
std::vector<std::uint8_t> encode_v2i_message(const FixWithheld& notice, const MessageHeader& header,
                                             const security::SigningKey* signer);

// Unsigned, with the header taken from the body (announcement: its generation time and sequence;
// correction: sweep time and sequence; advertisement, refusal, fix withheld: zeros): for tests about
// something else and tools in insecure mode.
std::vector<std::uint8_t> encode_v2i_message(const VehicleAnnouncement& announcement);
std::vector<std::uint8_t> encode_v2i_message(const Correction& correction);
std::vector<std::uint8_t> encode_v2i_message(const RsuAdvertisement& advertisement);
std::vector<std::uint8_t> encode_v2i_message(const AnnouncementRefusal& refusal);
std::vector<std::uint8_t> encode_v2i_message(const FixWithheld& notice);

}  // namespace rsu::v2i
