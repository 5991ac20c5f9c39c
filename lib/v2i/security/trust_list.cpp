// SPDX-License-Identifier: Apache-2.0
#include "v2i/security/trust_list.h"

#include <algorithm>
#include <charconv>
#include <stdexcept>

#include "v2i/security/key_text.h"

namespace rsu::v2i::security {
namespace {

[[noreturn]] void fail(std::string_view source, int line, const std::string& what) {
  throw std::invalid_argument(std::string(source) + ":" + std::to_string(line) + ": " + what);
}

std::vector<std::uint64_t> parse_ids(const std::string& text, std::string_view source, int line) {
  std::vector<std::uint64_t> ids;
  std::string_view rest = text;
  while (true) {
    const std::size_t comma = rest.find(',');
    const std::string_view item = rest.substr(0, comma);
    std::uint64_t id = 0;
    const auto [end, ec] = std::from_chars(item.data(), item.data() + item.size(), id);
    if (item.empty() || ec != std::errc{} || end != item.data() + item.size() || id == 0) {
      fail(source, line, "ids must be non-zero decimal numbers separated by commas, got \"" + text + "\"");
    }
    ids.push_back(id);
    if (comma == std::string_view::npos) {
      break;
    }
    rest = rest.substr(comma + 1);
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

}  // namespace

const char* to_string(SignerRole role) {
  return role == SignerRole::kRsu ? "rsu" : "vehicle";
}

bool TrustEntry::may_sign_for(std::uint64_t id) const {
  return std::find(ids.begin(), ids.end(), id) != ids.end();
}

void TrustList::add(const TrustEntry& entry) {
  if (entry.ids.empty()) {
    throw std::invalid_argument("a trust-list entry needs the ids its key may sign for");
  }
  const KeyId id = key_id_of(entry.public_key);
  if (!entries_.emplace(id, entry).second) {
    throw std::invalid_argument("key " + to_hex(id) + " is listed twice");
  }
}

const TrustEntry* TrustList::find(const KeyId& key_id) const {
  const auto it = entries_.find(key_id);
  return it == entries_.end() ? nullptr : &it->second;
}

std::size_t TrustList::count(SignerRole role) const {
  return static_cast<std::size_t>(std::count_if(entries_.begin(), entries_.end(),
                                                [role](const auto& e) { return e.second.role == role; }));
}

TrustList parse_trust_list_text(std::string_view text, std::string_view source) {
  TrustList list;
  for (const TextLine& line : meaningful_lines(text)) {
    if (line.fields.size() != 3) {
      fail(source, line.number, "expected \"<rsu|vehicle> <public key, 64 hex digits> <ids, e.g. 7,8>\"");
    }
    TrustEntry entry;
    if (line.fields[0] == "rsu") {
      entry.role = SignerRole::kRsu;
    } else if (line.fields[0] == "vehicle") {
      entry.role = SignerRole::kVehicle;
    } else {
      fail(source, line.number, "role must be \"rsu\" or \"vehicle\", got \"" + line.fields[0] + "\"");
    }
    if (!from_hex(line.fields[1], entry.public_key)) {
      fail(source, line.number, "public key must be exactly 64 hex digits");
    }
    entry.ids = parse_ids(line.fields[2], source, line.number);
    try {
      list.add(entry);
    } catch (const std::invalid_argument& e) {
      fail(source, line.number, e.what());
    }
  }
  return list;
}

std::string trust_entry_text(const TrustEntry& entry) {
  std::string ids;
  for (const std::uint64_t id : entry.ids) {
    ids += (ids.empty() ? "" : ",") + std::to_string(id);
  }
  return std::string(to_string(entry.role)) + " " + to_hex(entry.public_key) + " " + ids + "  # key id " +
         to_hex(key_id_of(entry.public_key)) + "\n";
}

}  // namespace rsu::v2i::security
