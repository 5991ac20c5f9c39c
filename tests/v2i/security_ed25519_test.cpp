// SPDX-License-Identifier: Apache-2.0
// Ed25519 against RFC 8032 §7.1 (test vectors 1-3), tampering, key ids and the key file text.
#include <gtest/gtest.h>

#include <sodium.h>

#include <string>
#include <vector>

#include "v2i/security/ed25519.h"
#include "v2i/security/key_text.h"

namespace rsu::v2i::security {
namespace {

template <std::size_t N>
std::array<std::uint8_t, N> hex_array(std::string_view hex) {
  std::array<std::uint8_t, N> out{};
  EXPECT_TRUE(from_hex(hex, out)) << hex;
  return out;
}

std::vector<std::uint8_t> hex_bytes(std::string_view hex) {
  std::vector<std::uint8_t> out(hex.size() / 2);
  EXPECT_TRUE(from_hex(hex, out)) << hex;
  return out;
}

struct Rfc8032Vector {
  const char* secret;
  const char* public_key;
  const char* message;
  const char* signature;
};

// RFC 8032 §7.1, TEST 1, TEST 2, TEST 3.
const Rfc8032Vector kVectors[] = {
    {"9d61b19deffd5a60ba844af492ec2cc44449c5697b326919703bac031cae7f60",
     "d75a980182b10ab7d54bfed3c964073a0ee172f3daa62325af021a68f707511a", "",
     "e5564300c360ac729086e2cc806e828a84877f1eb8e5d974d873e065224901555fb8821590a33bacc61e39701cf9b46bd25bf5f"
     "0595b"
     "be24655141438e7a100b"},
    {"4ccd089b28ff96da9db6c346ec114e0f5b8a319f35aba624da8cf6ed4fb8a6fb",
     "3d4017c3e843895a92b70aa74d1b7ebc9c982ccf2ec4968cc0cd55f12af4660c", "72",
     "92a009a9f0d4cab8720e820b5f642540a2b27b5416503f8fb3762223ebdb69da085ac1e43e15996e458f3613d0f11d8c387b2ea"
     "eb430"
     "2aeeb00d291612bb0c00"},
    {"c5aa8df43f9f837bedb7442f31dcb7b166d38535076f094b85ce3a2e0b4458f7",
     "fc51cd8e6218a1a38da47ed00230f0580816ed13ba3303ac5deb911548908025", "af82",
     "6291d657deec24024827e69c3abe01a30ce548a284743a445e3680d7db5ac3ac18ff9b538d16f290ae67f760984dc6594a7c15e"
     "971"
     "6ed28dc027beceea1ec40a"},
};

TEST(Ed25519, Rfc8032KnownAnswers) {
  for (const Rfc8032Vector& v : kVectors) {
    const SigningKey key(hex_array<kSeedBytes>(v.secret));
    EXPECT_EQ(to_hex(key.public_key()), v.public_key);
    const std::vector<std::uint8_t> message = hex_bytes(v.message);
    EXPECT_EQ(to_hex(key.sign(message)), v.signature);
    EXPECT_TRUE(verify_signature(hex_array<kPublicKeyBytes>(v.public_key), message,
                                 hex_array<kSignatureBytes>(v.signature)));
  }
}

TEST(Ed25519, EveryTamperedBitFailsVerification) {
  const SigningKey key(hex_array<kSeedBytes>(kVectors[2].secret));
  const std::vector<std::uint8_t> message = {1, 2, 3, 4, 5, 6, 7, 8};
  const Signature signature = key.sign(message);
  ASSERT_TRUE(verify_signature(key.public_key(), message, signature));
  for (std::size_t i = 0; i < message.size() * 8; ++i) {
    std::vector<std::uint8_t> m = message;
    m[i / 8] ^= static_cast<std::uint8_t>(1U << (i % 8));
    EXPECT_FALSE(verify_signature(key.public_key(), m, signature)) << "message bit " << i;
  }
  for (std::size_t i = 0; i < signature.size() * 8; ++i) {
    Signature s = signature;
    s[i / 8] ^= static_cast<std::uint8_t>(1U << (i % 8));
    EXPECT_FALSE(verify_signature(key.public_key(), message, s)) << "signature bit " << i;
  }
  const SigningKey other(hex_array<kSeedBytes>(kVectors[0].secret));
  EXPECT_FALSE(verify_signature(other.public_key(), message, signature));
  EXPECT_FALSE(verify_signature(key.public_key(), message, std::span(signature).first(63)));
  EXPECT_FALSE(verify_signature(key.public_key(), {}, signature));
}

TEST(Ed25519, KeyIdIsTheLastEightBytesOfSha256OfThePublicKey) {
  const PublicKey pk = hex_array<kPublicKeyBytes>(kVectors[0].public_key);
  std::array<std::uint8_t, crypto_hash_sha256_BYTES> hash{};
  crypto_hash_sha256(hash.data(), pk.data(), pk.size());
  KeyId expected{};
  std::copy(hash.begin() + 24, hash.end(), expected.begin());
  EXPECT_EQ(key_id_of(pk), expected);
  EXPECT_EQ(SigningKey(hex_array<kSeedBytes>(kVectors[0].secret)).key_id(), expected);
  EXPECT_NE(key_id_of(hex_array<kPublicKeyBytes>(kVectors[1].public_key)), expected);
}

TEST(Ed25519, HexRoundTripAndRefusals) {
  std::array<std::uint8_t, 3> out{};
  EXPECT_TRUE(from_hex("00aBff", out));
  EXPECT_EQ(out, (std::array<std::uint8_t, 3>{0x00, 0xAB, 0xFF}));
  EXPECT_EQ(to_hex(out), "00abff");
  EXPECT_FALSE(from_hex("00abf", out));
  EXPECT_FALSE(from_hex("00abfg", out));
  EXPECT_FALSE(from_hex("00abff00", out));
}

TEST(KeyText, SecretAndPublicKeysRoundTrip) {
  const SigningKey key(hex_array<kSeedBytes>(kVectors[1].secret));
  const std::string secret = secret_key_text(key);
  EXPECT_NE(secret.find(to_hex(key.key_id())), std::string::npos);  // named in the comment
  EXPECT_EQ(parse_secret_key_text(secret, "k").public_key(), key.public_key());
  EXPECT_EQ(parse_public_key_text(public_key_text(key.public_key()), "p"), key.public_key());
  // Comments, blank lines and CRLF are fine.
  EXPECT_EQ(
      parse_public_key_text(
          "\n# x\r\n  ed25519-public-key " + std::string(kVectors[1].public_key) + "  # trailing\r\n", "p"),
      key.public_key());
}

TEST(KeyText, BrokenFilesAreLocatedErrors) {
  const std::string pk = kVectors[0].public_key;
  const auto error = [](auto parse) -> std::string {
    try {
      parse();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_EQ(error([] { parse_public_key_text("# nothing\n", "a.pub"); }),
            "a.pub: no key (expected a line \"ed25519-public-key <64 hex digits>\")");
  EXPECT_EQ(error([&] { parse_public_key_text("\ned25519-public-key " + pk.substr(2) + "\n", "a.pub"); }),
            "a.pub:2: key must be exactly 64 hex digits");
  EXPECT_EQ(error([&] { parse_public_key_text("ed25519-secret-key " + pk + "\n", "a.pub"); }),
            "a.pub:1: expected \"ed25519-public-key\", got \"ed25519-secret-key\"");
  EXPECT_EQ(error([&] { parse_secret_key_text("ed25519-secret-key " + pk + " extra\n", "a.key"); }),
            "a.key:1: expected \"ed25519-secret-key <64 hex digits>\"");
  EXPECT_EQ(error([&] {
              parse_secret_key_text("ed25519-secret-key " + pk + "\ned25519-secret-key " + pk + "\n",
                                    "a.key");
            }),
            "a.key:2: more than one key line");
}

}  // namespace
}  // namespace rsu::v2i::security
