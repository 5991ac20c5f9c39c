// SPDX-License-Identifier: Apache-2.0
// Trust-list text: entries, the binding of keys to ids, and located errors.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "test_keys.h"
#include "v2i/security/key_text.h"
#include "v2i/security/trust_list.h"

namespace rsu::v2i::security {
namespace {

std::string error_of(std::string_view text) {
  try {
    parse_trust_list_text(text, "trust.list");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

TEST(TrustList, ParsesEntriesAndBindsKeysToIds) {
  const SigningKey rsu = key_from(1);
  const SigningKey car = key_from(2);
  const std::string text = "# trust list\n\nrsu " + to_hex(rsu.public_key()) + " 1\nvehicle " +
                           to_hex(car.public_key()) + " 8,7,8   # two cars\n";
  const TrustList list = parse_trust_list_text(text, "trust.list");
  ASSERT_EQ(list.size(), 2U);
  EXPECT_EQ(list.count(SignerRole::kRsu), 1U);
  const TrustEntry* r = list.find(rsu.key_id());
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->role, SignerRole::kRsu);
  EXPECT_EQ(r->public_key, rsu.public_key());
  EXPECT_TRUE(r->may_sign_for(1));
  EXPECT_FALSE(r->may_sign_for(2));
  const TrustEntry* c = list.find(car.key_id());
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->ids, (std::vector<std::uint64_t>{7, 8}));  // sorted, duplicates removed
  EXPECT_FALSE(c->may_sign_for(9));
  EXPECT_EQ(list.find(key_from(3).key_id()), nullptr);
}

TEST(TrustList, EntryTextRoundTrips) {
  const SigningKey car = key_from(4);
  const TrustEntry entry{car.public_key(), SignerRole::kVehicle, {3, 12}};
  const std::string line = trust_entry_text(entry);
  EXPECT_NE(line.find(to_hex(car.key_id())), std::string::npos);
  const TrustList list = parse_trust_list_text(line, "x");
  ASSERT_NE(list.find(car.key_id()), nullptr);
  EXPECT_EQ(list.find(car.key_id())->ids, entry.ids);
}

TEST(TrustList, BrokenLinesAreLocatedErrors) {
  const std::string pk = to_hex(key_from(5).public_key());
  EXPECT_EQ(error_of("\nvehicle " + pk + "\n"),
            "trust.list:2: expected \"<rsu|vehicle> <public key, 64 hex digits> <ids, e.g. 7,8>\"");
  EXPECT_EQ(error_of("car " + pk + " 1\n"), "trust.list:1: role must be \"rsu\" or \"vehicle\", got \"car\"");
  EXPECT_EQ(error_of("rsu " + pk.substr(1) + " 1\n"),
            "trust.list:1: public key must be exactly 64 hex digits");
  for (const char* ids : {"0", "1,,2", "x", "-1", "1,", "99999999999999999999"}) {
    EXPECT_EQ(error_of("rsu " + pk + " " + ids + "\n"),
              "trust.list:1: ids must be non-zero decimal numbers separated by commas, got \"" +
                  std::string(ids) + "\"")
        << ids;
  }
  EXPECT_EQ(error_of("rsu " + pk + " 1\nvehicle " + pk + " 2\n"),
            "trust.list:2: key " + to_hex(key_from(5).key_id()) + " is listed twice");
  EXPECT_THROW(TrustList().add({key_from(6).public_key(), SignerRole::kRsu, {}}), std::invalid_argument);
}

// The lines every key and trust-list file is read by: comments and blank lines gone, fields split on
// blanks (spaces, tabs, a CRLF file's CR), each line numbered as an editor numbers it.
TEST(KeyText, MeaningfulLinesKeepTheirNumbers) {
  const std::string text =
      "# a comment\n"
      "\n"
      "ed25519-public-key  abc\t def # trailing comment\r\n"
      "   \t\r\n"
      "#only\n"
      "vehicle 7\r\n"
      "last line without newline";
  const std::vector<TextLine> lines = meaningful_lines(text);
  ASSERT_EQ(lines.size(), 3U);
  EXPECT_EQ(lines[0].number, 3);
  EXPECT_EQ(lines[0].fields, (std::vector<std::string>{"ed25519-public-key", "abc", "def"}));
  EXPECT_EQ(lines[1].number, 6);
  EXPECT_EQ(lines[1].fields, (std::vector<std::string>{"vehicle", "7"}));
  EXPECT_EQ(lines[2].number, 7);
  EXPECT_EQ(lines[2].fields, (std::vector<std::string>{"last", "line", "without", "newline"}));
  EXPECT_TRUE(meaningful_lines("").empty());
  EXPECT_TRUE(meaningful_lines("\n\n# nothing\n\r\n").empty());
  EXPECT_EQ(meaningful_lines("a#b c").front().fields, (std::vector<std::string>{"a"}));
}

}  // namespace
}  // namespace rsu::v2i::security
