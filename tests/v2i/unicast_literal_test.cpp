// SPDX-License-Identifier: Apache-2.0
// is_unicast_ip_literal (announcement_validation.h): a reply_to address must be a numeric literal of one
// host, never a name, a network, a multicast group or a broadcast. The classes are written out here from
// the RFCs (RFC 1122 3.2.1.3: 0.0.0.0/8 "this network"; RFC 5771: 224.0.0.0/4 multicast; RFC 919:
// 255.255.255.255 broadcast; RFC 4291 2.5.2, 2.7: :: unspecified, ff00::/8 multicast; 2.5.5.2: an
// IPv4-mapped address is its IPv4 address).
#include <gtest/gtest.h>

#include <string>

#include "v2i/announcement_validation.h"

namespace rsu::v2i {
namespace unicast_literal_test {

TEST(UnicastIpLiteral, HostAddressesAreUnicast) {
  for (const char* host :
       {"192.0.2.7", "10.0.0.1", "127.0.0.1", "1.0.0.0", "223.255.255.255", "240.0.0.1", "255.255.255.254",
        "2001:db8::1", "::1", "fe80::1", "::ffff:192.0.2.7", "2001:0db8:0000:0000:0000:0000:0000:0001"}) {
    EXPECT_TRUE(is_unicast_ip_literal(host)) << host;
  }
}

TEST(UnicastIpLiteral, NetworksGroupsAndBroadcastAreNot) {
  for (const char* many :
       {"0.0.0.0", "0.1.2.3", "224.0.0.1", "239.255.255.250", "230.1.2.3", "255.255.255.255", "::", "ff02::1",
        "ff05::1:3", "FF0E::101", "::ffff:224.0.0.1", "::ffff:255.255.255.255", "::ffff:0.0.0.0"}) {
    EXPECT_FALSE(is_unicast_ip_literal(many)) << many;
  }
}

TEST(UnicastIpLiteral, NamesAndMalformedTextAreNot) {
  for (const char* text :
       {"", "localhost", "rsu.example", "192.0.2", "192.0.2.256", "192.0.2.7:5000", " 192.0.2.7",
        "192.0.2.7 ", "[2001:db8::1]", "2001:db8::1::2", "1.2.3.4.5", "::ffff:192.0.2", "192.0.2.-1"}) {
    EXPECT_FALSE(is_unicast_ip_literal(text)) << '"' << text << '"';
  }
  EXPECT_FALSE(is_unicast_ip_literal(std::string("192.0.2.7\0", 10)));
}

}  // namespace unicast_literal_test
}  // namespace rsu::v2i
