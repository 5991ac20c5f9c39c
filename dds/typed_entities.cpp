// SPDX-License-Identifier: Apache-2.0
#include "dds/typed_entities.h"

namespace rsu::dds {

std::string ros_topic(const std::string& ros_name) {
  const std::size_t skip = (!ros_name.empty() && ros_name.front() == '/') ? 1 : 0;
  return "rt/" + ros_name.substr(skip);
}

Topic::Topic(const Participant& participant, const std::string& name,
             const dds_topic_descriptor_t& descriptor)
    : name_(name),
      entity_(
          check_entity(dds_create_topic(participant.handle(), &descriptor, name.c_str(), nullptr, nullptr),
                       "creating topic " + name)) {}

}  // namespace rsu::dds
