// SPDX-License-Identifier: Apache-2.0
// The installed vehicle client library's version (rsu-vehicle-client.so, issue 14): what a program built
// against the package can print and check.
#pragma once

namespace rsu::vehicle_client {

// "MAJOR.MINOR.PATCH" of the project the library was built from.
const char* library_version();

}  // namespace rsu::vehicle_client
