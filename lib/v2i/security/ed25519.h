// SPDX-License-Identifier: Apache-2.0
// Ed25519 signatures (RFC 8032, pure Ed25519) with libsodium, and the key id that names a public key on
// the wire (proto/v2i.proto). Pure computation: keys come from seeds the caller supplies (rsu-keygen
// draws them from the OS), nothing here reads files or clocks.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace rsu::v2i::security {

inline constexpr std::size_t kSeedBytes = 32;       // RFC 8032's 32-byte private key
inline constexpr std::size_t kPublicKeyBytes = 32;  // RFC 8032's encoded point A
inline constexpr std::size_t kSignatureBytes = 64;  // R || S
inline constexpr std::size_t kKeyIdBytes = 8;       // proto/v2i.proto: signer_key_id

using Seed = std::array<std::uint8_t, kSeedBytes>;
using PublicKey = std::array<std::uint8_t, kPublicKeyBytes>;
using Signature = std::array<std::uint8_t, kSignatureBytes>;
using KeyId = std::array<std::uint8_t, kKeyIdBytes>;

// Initialises libsodium once; idempotent and thread-safe (libsodium guards it). Called by the
// constructors and functions below, so callers never need to. Throws std::runtime_error if libsodium
// cannot initialise (it then must not be used).
void ensure_sodium_initialized();

// The last 8 bytes of SHA-256(public key), like IEEE 1609.2's HashedId8 (the low-order 8 bytes of a
// certificate's SHA-256). Names the key in a trust list; the signature binds the full key.
KeyId key_id_of(const PublicKey& public_key);

// True when `signature` is a valid Ed25519 signature of exactly `message` by `public_key`. A signature
// of the wrong length is simply invalid. libsodium rejects non-canonical S and small-order keys.
bool verify_signature(const PublicKey& public_key, std::span<const std::uint8_t> message,
                      std::span<const std::uint8_t> signature);

// An Ed25519 key pair. The secret part is wiped when the object is destroyed.
class SigningKey {
 public:
  // Deterministic: the same seed gives the same keys (RFC 8032 §5.1.5).
  explicit SigningKey(const Seed& seed);
  SigningKey(const SigningKey& other);
  SigningKey& operator=(const SigningKey& other);
  ~SigningKey();

  Signature sign(std::span<const std::uint8_t> message) const;
  const PublicKey& public_key() const { return public_key_; }
  const KeyId& key_id() const { return key_id_; }
  const Seed& seed() const { return seed_; }  // for writing the secret key file

 private:
  Seed seed_{};
  std::array<std::uint8_t, 64> secret_{};  // libsodium's expanded form: seed || public key
  PublicKey public_key_{};
  KeyId key_id_{};
};

// Lower-case hex of bytes, and its inverse (false on a wrong length or a non-hex digit).
std::string to_hex(std::span<const std::uint8_t> bytes);
bool from_hex(std::string_view text, std::span<std::uint8_t> out);

}  // namespace rsu::v2i::security
