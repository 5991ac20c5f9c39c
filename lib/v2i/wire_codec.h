// Encoding and decoding of V2iMessage datagrams (proto/v2i.proto) to and from the plain structs of
// messages.h. Decoding checks structure only (parses, has a body, covariances have 9 values); field
// plausibility is announcement_validation.h's job. Never throws, whatever the bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <variant>
#include <vector>

#include "v2i/messages.h"

namespace rsu::v2i {

// Largest datagram accepted or produced: an IPv6 minimum-MTU packet (1280) minus the IPv6 and UDP
// headers, so a message is never fragmented on any link. An announcement is about 150 bytes.
inline constexpr std::size_t kMaxDatagramBytes = 1232;

enum class DecodeStatus : std::uint8_t {
  kOk,
  kEmpty,
  kTooLarge,
  kParseError,           // not a V2iMessage in protobuf wire format
  kNoBody,               // parsed, but no announcement/correction/advertisement in it
  kMalformedCovariance,  // a covariance without exactly 9 values
  kCount,
};

const char* to_string(DecodeStatus status);

using MessageBody = std::variant<std::monostate, VehicleAnnouncement, Correction, RsuAdvertisement>;

struct DecodedMessage {
  DecodeStatus status = DecodeStatus::kParseError;
  MessageBody body;  // set only when status is kOk; carries the envelope's protocol_version
};

DecodedMessage decode_v2i_message(std::span<const std::uint8_t> bytes);

// Serialise one message (the struct's protocol_version goes in the envelope). Empty on failure,
// e.g. a result over kMaxDatagramBytes.
std::vector<std::uint8_t> encode_v2i_message(const VehicleAnnouncement& announcement);
std::vector<std::uint8_t> encode_v2i_message(const Correction& correction);
std::vector<std::uint8_t> encode_v2i_message(const RsuAdvertisement& advertisement);

}  // namespace rsu::v2i
