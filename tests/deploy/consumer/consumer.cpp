// SPDX-License-Identifier: Apache-2.0
// A program outside the project built against the installed vehicle client package (tests/deploy/
// install_consumer.sh): it reads a vehicle key with the library's own parser (its key id printed), parses an
// RSU endpoint and prints the library's version, so its headers, its exported symbols and its dependencies
// are all used.
#include <cstdio>
#include <fstream>
#include <sstream>

#include "edge/address_text.h"
#include "v2i/security/key_text.h"
#include "vehicle_client/library_version.h"
#include "vehicle_client/vehicle_client.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: consumer KEY_FILE HOST:PORT\n");
    return 2;
  }
  std::ifstream in(argv[1]);
  std::stringstream text;
  text << in.rdbuf();
  const auto key = rsu::v2i::security::parse_secret_key_text(text.str(), argv[1]);
  const auto rsu = rsu::edge::parse_udp_endpoint(argv[2]);
  std::printf("rsu-vehicle-client %s: key id ", rsu::vehicle_client::library_version());
  for (const auto byte : key.key_id())
    std::printf("%02x", static_cast<unsigned>(byte));
  std::printf(", rsu %s\n", rsu::edge::to_text(rsu).c_str());
  return 0;
}
