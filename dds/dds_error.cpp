// SPDX-License-Identifier: Apache-2.0
#include "dds/dds_error.h"

namespace rsu::dds {

DdsError::DdsError(const std::string& what, dds_return_t code)
    : std::runtime_error("dds: " + what + ": " + dds_strretcode(code)), code_(code) {}

dds_entity_t check_entity(dds_entity_t entity, const std::string& what) {
  if (entity < 0)
    throw DdsError(what, entity);
  return entity;
}

void check(dds_return_t code, const std::string& what) {
  if (code < 0)
    throw DdsError(what, code);
}

}  // namespace rsu::dds
