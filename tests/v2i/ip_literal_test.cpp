// SPDX-License-Identifier: Apache-2.0
// The one parser of numeric addresses (reply_to, a datagram's sender): what it takes, what it refuses,
// which literals name one host, and when two spellings name the same one. The expected bytes are written
// out by hand from the RFCs' notations (RFC 4291 §2.2 and §2.5.5.2), not taken from the C library.
#include "v2i/ip_literal.h"

#include <gtest/gtest.h>

#include <array>
#include <string>
#include <string_view>

namespace rsu::v2i {
namespace {

using Bytes = std::array<unsigned char, 16>;

Bytes mapped(unsigned char a, unsigned char b, unsigned char c, unsigned char d) {
  return {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff, a, b, c, d};
}

TEST(IpLiteral, Ipv4IsHeldAsIpv4MappedIpv6) {
  const auto a = parse_ip_literal("192.0.2.7");
  ASSERT_TRUE(a);
  EXPECT_TRUE(a->ipv4);
  EXPECT_EQ(a->bytes, mapped(192, 0, 2, 7));
  const auto b = parse_ip_literal("255.255.255.255");
  ASSERT_TRUE(b);
  EXPECT_EQ(b->bytes, mapped(255, 255, 255, 255));
}

TEST(IpLiteral, Ipv6InItsSpellings) {
  const Bytes doc = {0x20, 0x01, 0x0d, 0xb8, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x01};
  for (const char* text : {"2001:db8::1", "2001:0db8:0000:0000:0000:0000:0000:0001", "2001:DB8:0:0:0:0:0:1",
                           "2001:db8:0::0:1"}) {
    const auto a = parse_ip_literal(text);
    ASSERT_TRUE(a) << text;
    EXPECT_FALSE(a->ipv4) << text;
    EXPECT_EQ(a->bytes, doc) << text;
  }
  const auto loopback = parse_ip_literal("::1");
  ASSERT_TRUE(loopback);
  EXPECT_EQ(loopback->bytes, (Bytes{0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1}));
  const auto dual = parse_ip_literal("::ffff:192.0.2.7");  // the dual-stack spelling of an IPv4 host
  ASSERT_TRUE(dual);
  EXPECT_FALSE(dual->ipv4);
  EXPECT_EQ(dual->bytes, mapped(192, 0, 2, 7));
}

TEST(IpLiteral, RefusesWhatIsNotOneWholeLiteral) {
  const std::string too_long(65, '1');
  const std::string with_nul("192.0.2.1\0junk", 14);
  for (const std::string_view text :
       {std::string_view(""), std::string_view("localhost"), std::string_view("rsu.example"),
        std::string_view("192.0.2.7:40000"), std::string_view("[2001:db8::1]"),
        std::string_view("fe80::1%eth0"), std::string_view("256.0.0.1"), std::string_view("192.0.2"),
        std::string_view("192.0.2.7.1"), std::string_view(" 192.0.2.7"), std::string_view("192.0.2.7 "),
        std::string_view("2001:db8:::1"), std::string_view("1:2:3:4:5:6:7:8:9"), std::string_view("-1.0.0.0"),
        std::string_view(too_long), std::string_view(with_nul)}) {
    EXPECT_FALSE(parse_ip_literal(text)) << "\"" << std::string(text) << "\"";
  }
  // The longest spellings parse (an IPv6 literal with a dotted tail is at most 45 characters).
  const auto longest = parse_ip_literal("0000:0000:0000:0000:0000:ffff:255.255.255.255");
  ASSERT_TRUE(longest);
  EXPECT_EQ(longest->bytes, mapped(255, 255, 255, 255));
}

bool unicast(std::string_view text) {
  const auto a = parse_ip_literal(text);
  EXPECT_TRUE(a) << text;
  return a && is_unicast(*a);
}

TEST(IpLiteral, UnicastNamesOneHost) {
  for (const char* host : {"192.0.2.7", "127.0.0.1", "10.0.0.1", "1.0.0.0", "223.255.255.255", "240.0.0.1",
                           "255.255.255.254", "::1", "2001:db8::1", "fe80::1", "::ffff:192.0.2.7"})
    EXPECT_TRUE(unicast(host)) << host;
  // Unspecified ("this network", 0.0.0.0/8, and ::), multicast (224.0.0.0/4, ff00::/8), IPv4 broadcast.
  for (const char* group : {"0.0.0.0", "0.1.2.3", "224.0.0.1", "239.255.255.255", "255.255.255.255",
                            "::", "ff02::1", "ff0e::101"})
    EXPECT_FALSE(unicast(group)) << group;
}

// The dual-stack spelling of an IPv4 address names the same host and is judged by the IPv4 rules: a
// mapped multicast group or broadcast is no more one host than its dotted spelling.
TEST(IpLiteral, MappedIpv4IsJudgedAsIpv4) {
  for (const char* group : {"::ffff:224.0.0.1", "::ffff:239.1.2.3", "::ffff:255.255.255.255",
                            "::ffff:0.0.0.0", "::ffff:0.1.2.3", "::ffff:e000:1"})
    EXPECT_FALSE(unicast(group)) << group;
  EXPECT_TRUE(unicast("::ffff:c000:207"));  // 192.0.2.7
}

TEST(IpLiteral, SameHostWhateverTheSpelling) {
  EXPECT_TRUE(same_host("127.0.0.1", "127.0.0.1"));
  EXPECT_TRUE(same_host("127.0.0.1", "::ffff:127.0.0.1"));
  EXPECT_TRUE(same_host("::ffff:7f00:1", "127.0.0.1"));
  EXPECT_TRUE(same_host("2001:db8::1", "2001:0DB8:0:0:0:0:0:1"));
  EXPECT_FALSE(same_host("127.0.0.1", "127.0.0.2"));
  EXPECT_FALSE(same_host("::1", "127.0.0.1"));  // IPv6 loopback is another address
  EXPECT_FALSE(same_host("2001:db8::1", "2001:db8::2"));
  EXPECT_FALSE(same_host("localhost", "localhost"));  // names are not literals: never the same host
  EXPECT_FALSE(same_host("", ""));
  EXPECT_FALSE(same_host("127.0.0.1", "127.0.0.1:40000"));
}

}  // namespace
}  // namespace rsu::v2i
