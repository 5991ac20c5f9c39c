// SPDX-License-Identifier: Apache-2.0
#include "core/datagram_outcome.h"

namespace rsu::core {

const char* to_string(DatagramStage stage) {
  switch (stage) {
    case DatagramStage::kAccepted:
      return "accepted";
    case DatagramStage::kFloodLimited:
      return "flood_limited";
    case DatagramStage::kDecode:
      return "decode";
    case DatagramStage::kAuthentication:
      return "auth";
    case DatagramStage::kNotAnnouncement:
      return "not_announcement";
    case DatagramStage::kValidation:
      return "validation";
    case DatagramStage::kReplyToMismatch:
      return "reply_to_mismatch";
    case DatagramStage::kRegistry:
      return "registry";
    case DatagramStage::kBeyondVerification:
      return "beyond_verification_radius";
    case DatagramStage::kFromSelf:
      return "from_self";
    case DatagramStage::kNotFresher:
      return "not_fresher";
    case DatagramStage::kCount:
      break;
  }
  return "unknown";
}

const char* to_string(ReplyToCheck check) {
  switch (check) {
    case ReplyToCheck::kMatches:
      return "matches";
    case ReplyToCheck::kAddress:
      return "address";
    case ReplyToCheck::kPort:
      return "port";
    case ReplyToCheck::kReplaced:
      return "replaced";
    case ReplyToCheck::kCount:
      break;
  }
  return "unknown";
}

std::string DatagramOutcome::reason() const {
  std::string out = to_string(stage);
  switch (stage) {
    case DatagramStage::kDecode:
      return out + ":" + v2i::to_string(decode);
    case DatagramStage::kAuthentication:
      return out + ":" + v2i::to_string(auth);
    case DatagramStage::kValidation:
      return out + ":" + v2i::to_string(validation);
    case DatagramStage::kReplyToMismatch:
      return out + ":" + to_string(reply_to);
    case DatagramStage::kAccepted:
    case DatagramStage::kRegistry:
      return out + ":" + v2i::to_string(upsert);
    default:
      return out;
  }
}

}  // namespace rsu::core
