// SPDX-License-Identifier: Apache-2.0
// Cyclone DDS return codes as exceptions carrying Cyclone's own text (dds_strretcode), so a failure
// reads e.g. "dds: creating the reader of rt/points: Precondition Not Met".
#pragma once

#include <dds/dds.h>

#include <stdexcept>
#include <string>

namespace rsu::dds {

class DdsError : public std::runtime_error {
 public:
  DdsError(const std::string& what, dds_return_t code);
  dds_return_t code() const { return code_; }

 private:
  dds_return_t code_;
};

// Returns `entity` when it is a handle (> 0); throws DdsError naming `what` when it is an error code.
dds_entity_t check_entity(dds_entity_t entity, const std::string& what);
// Throws DdsError naming `what` when `code` is an error (< 0).
void check(dds_return_t code, const std::string& what);

}  // namespace rsu::dds
