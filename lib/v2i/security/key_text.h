// SPDX-License-Identifier: Apache-2.0
// The text formats of key files, parsed from TEXT the caller read (lib/ does no file I/O; rsud, the
// vehicle client and rsu-keygen read and write the files). Errors throw std::invalid_argument naming
// "<source>:<line>: what is wrong", like the YAML readers (io/yaml_field.h).
//
// Secret key file (written by rsu-keygen with mode 0600):
//     # comments and blank lines are ignored
//     ed25519-secret-key <64 hex digits: the 32-byte RFC 8032 private key (seed)>
// Public key file:
//     ed25519-public-key <64 hex digits: the 32-byte RFC 8032 public key>
// Exactly one key line per file.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "v2i/security/ed25519.h"

namespace rsu::v2i::security {

SigningKey parse_secret_key_text(std::string_view text, std::string_view source);
PublicKey parse_public_key_text(std::string_view text, std::string_view source);

std::string secret_key_text(const SigningKey& key);  // includes a comment with the key id
std::string public_key_text(const PublicKey& key);

// The meaningful lines of a key or trust-list text: comments ('#' to the end of the line) and blank
// lines removed, fields split on blanks, each with its 1-based line number.
struct TextLine {
  int number = 0;
  std::vector<std::string> fields;
};
std::vector<TextLine> meaningful_lines(std::string_view text);

}  // namespace rsu::v2i::security
