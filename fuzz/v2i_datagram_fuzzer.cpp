// SPDX-License-Identifier: Apache-2.0
// Fuzzes the V2I datagram parser (wire_codec.h), the message authenticator (signature, signer's
// rights, time and sequence windows; message_authenticator.h) and the announcement checks behind it
// (announcement_validation.h): whatever arrives on the announcement port must decode to a status,
// authenticate to a verdict, validate to a reason, and never crash. A decoded message re-encodes to
// bytes that decode again. The seeds are signed with fuzz_keys.h's keys.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <variant>

#include "common/time.h"
#include "fuzz_keys.h"
#include "v2i/announcement_validation.h"
#include "v2i/message_authenticator.h"
#include "v2i/wire_codec.h"

namespace {

using namespace rsu::v2i;

// The receive time every announcement is checked against (an arbitrary 2024 instant on the common
// clock); validation sees both this and the message's own generation time, so the age checks and
// the checks after them are reached.
constexpr rsu::TimeNs kNow = 1'718'000'000LL * rsu::kNsPerSecond;

template <typename Message>
void check_reencodes(const Message& message, std::size_t body_index) {
  const std::vector<std::uint8_t> bytes = encode_v2i_message(message);
  if (bytes.empty()) {
    return;  // documented: too large to send (cannot happen for a decoded datagram, but allowed)
  }
  const DecodedMessage again = decode_v2i_message(bytes);
  if (again.status != DecodeStatus::kOk || again.body.index() != body_index) {
    std::abort();  // what we encode we must be able to decode
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Signed mode, twice: a replay of the same bytes must never be accepted again.
  MessageAuthenticator authenticator(SecurityConfig{}, rsu::fuzz::fuzz_trust_list());
  const AuthenticatedMessage first =
      authenticator.authenticate(std::span<const std::uint8_t>(data, size), kNow);
  const AuthenticatedMessage again =
      authenticator.authenticate(std::span<const std::uint8_t>(data, size), kNow);
  (void)to_string(first.verdict);
  if (again.verdict == AuthVerdict::kAccepted) {
    std::abort();
  }
  const DecodedMessage decoded = decode_v2i_message(std::span<const std::uint8_t>(data, size));
  (void)to_string(decoded.status);
  if (decoded.status != DecodeStatus::kOk) {
    return 0;
  }
  if (const auto* a = std::get_if<VehicleAnnouncement>(&decoded.body)) {
    AnnouncementValidator validator;
    (void)to_string(validator.check(*a, kNow));
    (void)to_string(validator.check(*a, a->generation_time));
    (void)is_unicast_ip_literal(a->reply_to.address);
    check_reencodes(*a, decoded.body.index());
  } else if (const auto* c = std::get_if<Correction>(&decoded.body)) {
    check_reencodes(*c, decoded.body.index());
  } else if (const auto* r = std::get_if<RsuAdvertisement>(&decoded.body)) {
    check_reencodes(*r, decoded.body.index());
  } else if (const auto* f = std::get_if<AnnouncementRefusal>(&decoded.body)) {
    check_reencodes(*f, decoded.body.index());
  } else if (const auto* w = std::get_if<FixWithheld>(&decoded.body)) {
    (void)to_string(w->reason);
    check_reencodes(*w, decoded.body.index());
  }
  return 0;
}
