// SPDX-License-Identifier: Apache-2.0
#include "vehicle_client/library_version.h"

namespace rsu::vehicle_client {

const char* library_version() {
  return RSU_VEHICLE_CLIENT_VERSION;
}

}  // namespace rsu::vehicle_client
