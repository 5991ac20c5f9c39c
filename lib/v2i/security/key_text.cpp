// SPDX-License-Identifier: Apache-2.0
#include "v2i/security/key_text.h"

#include <sodium.h>

#include <stdexcept>

namespace rsu::v2i::security {
namespace {

constexpr std::string_view kSecretTag = "ed25519-secret-key";
constexpr std::string_view kPublicTag = "ed25519-public-key";

[[noreturn]] void fail(std::string_view source, int line, const std::string& what) {
  std::string where(source);
  if (line > 0) {
    where += ":" + std::to_string(line);
  }
  throw std::invalid_argument(where + ": " + what);
}

// The 32 bytes of the one "<tag> <hex>" line of a key file.
std::array<std::uint8_t, 32> read_key_line(std::string_view text, std::string_view source,
                                           std::string_view tag) {
  const std::vector<TextLine> lines = meaningful_lines(text);
  if (lines.empty()) {
    fail(source, 0, "no key (expected a line \"" + std::string(tag) + " <64 hex digits>\")");
  }
  if (lines.size() > 1) {
    fail(source, lines[1].number, "more than one key line");
  }
  const TextLine& line = lines.front();
  if (line.fields.front() != tag) {
    fail(source, line.number, "expected \"" + std::string(tag) + "\", got \"" + line.fields.front() + "\"");
  }
  if (line.fields.size() != 2) {
    fail(source, line.number, "expected \"" + std::string(tag) + " <64 hex digits>\"");
  }
  std::array<std::uint8_t, 32> bytes{};
  if (!from_hex(line.fields[1], bytes)) {
    fail(source, line.number, "key must be exactly 64 hex digits");
  }
  return bytes;
}

}  // namespace

std::vector<TextLine> meaningful_lines(std::string_view text) {
  std::vector<TextLine> out;
  int number = 0;
  while (!text.empty()) {
    ++number;
    const std::size_t end = text.find('\n');
    std::string_view line = text.substr(0, end);
    text = end == std::string_view::npos ? std::string_view{} : text.substr(end + 1);
    line = line.substr(0, line.find('#'));
    TextLine parsed{number, {}};
    std::size_t i = 0;
    while (i < line.size()) {
      const std::size_t start = line.find_first_not_of(" \t\r", i);
      if (start == std::string_view::npos) {
        break;
      }
      const std::size_t stop = std::min(line.find_first_of(" \t\r", start), line.size());
      parsed.fields.emplace_back(line.substr(start, stop - start));
      i = stop;
    }
    if (!parsed.fields.empty()) {
      out.push_back(std::move(parsed));
    }
  }
  return out;
}

SigningKey parse_secret_key_text(std::string_view text, std::string_view source) {
  Seed seed = read_key_line(text, source, kSecretTag);
  SigningKey key(seed);
  sodium_memzero(seed.data(), seed.size());
  return key;
}

PublicKey parse_public_key_text(std::string_view text, std::string_view source) {
  return read_key_line(text, source, kPublicTag);
}

std::string secret_key_text(const SigningKey& key) {
  return "# Ed25519 secret key, key id " + to_hex(key.key_id()) + ". Keep private (mode 0600).\n" +
         std::string(kSecretTag) + " " + to_hex(key.seed()) + "\n";
}

std::string public_key_text(const PublicKey& key) {
  return "# Ed25519 public key, key id " + to_hex(key_id_of(key)) + "\n" + std::string(kPublicTag) + " " +
         to_hex(key) + "\n";
}

}  // namespace rsu::v2i::security
