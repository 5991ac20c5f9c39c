// SPDX-License-Identifier: Apache-2.0
#include "v2i/security/ed25519.h"

#include <sodium.h>

#include <stdexcept>

namespace rsu::v2i::security {

void ensure_sodium_initialized() {
  // sodium_init() returns 0 the first time, 1 when already done, -1 on failure.
  if (sodium_init() < 0) {
    throw std::runtime_error("libsodium failed to initialise");
  }
}

KeyId key_id_of(const PublicKey& public_key) {
  ensure_sodium_initialized();
  std::array<std::uint8_t, crypto_hash_sha256_BYTES> hash{};
  crypto_hash_sha256(hash.data(), public_key.data(), public_key.size());
  KeyId id{};
  std::copy(hash.end() - static_cast<std::ptrdiff_t>(kKeyIdBytes), hash.end(), id.begin());
  return id;
}

bool verify_signature(const PublicKey& public_key, std::span<const std::uint8_t> message,
                      std::span<const std::uint8_t> signature) {
  static_assert(kSignatureBytes == crypto_sign_BYTES && kPublicKeyBytes == crypto_sign_PUBLICKEYBYTES);
  if (signature.size() != kSignatureBytes) {
    return false;
  }
  ensure_sodium_initialized();
  return crypto_sign_verify_detached(signature.data(), message.data(), message.size(), public_key.data()) ==
         0;
}

SigningKey::SigningKey(const Seed& seed) : seed_(seed) {
  static_assert(kSeedBytes == crypto_sign_SEEDBYTES && 64 == crypto_sign_SECRETKEYBYTES);
  ensure_sodium_initialized();
  crypto_sign_seed_keypair(public_key_.data(), secret_.data(), seed_.data());
  key_id_ = key_id_of(public_key_);
}

SigningKey::SigningKey(const SigningKey& other) = default;
SigningKey& SigningKey::operator=(const SigningKey& other) = default;

SigningKey::~SigningKey() {
  sodium_memzero(seed_.data(), seed_.size());
  sodium_memzero(secret_.data(), secret_.size());
}

Signature SigningKey::sign(std::span<const std::uint8_t> message) const {
  Signature signature{};
  crypto_sign_detached(signature.data(), nullptr, message.data(), message.size(), secret_.data());
  return signature;
}

std::string to_hex(std::span<const std::uint8_t> bytes) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  out.reserve(2 * bytes.size());
  for (const std::uint8_t b : bytes) {
    out.push_back(kDigits[b >> 4]);
    out.push_back(kDigits[b & 0x0F]);
  }
  return out;
}

bool from_hex(std::string_view text, std::span<std::uint8_t> out) {
  if (text.size() != 2 * out.size()) {
    return false;
  }
  const auto digit = [](char c) -> int {
    if (c >= '0' && c <= '9')
      return c - '0';
    if (c >= 'a' && c <= 'f')
      return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
      return c - 'A' + 10;
    return -1;
  };
  for (std::size_t i = 0; i < out.size(); ++i) {
    const int hi = digit(text[2 * i]);
    const int lo = digit(text[2 * i + 1]);
    if (hi < 0 || lo < 0) {
      return false;
    }
    out[i] = static_cast<std::uint8_t>(hi << 4 | lo);
  }
  return true;
}

}  // namespace rsu::v2i::security
