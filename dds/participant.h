// SPDX-License-Identifier: Apache-2.0
// A DDS domain participant, RAII. One per process is the DDS norm (rsud has one; a test process may
// hold several: the first one's Cyclone configuration then applies to all of them, since Cyclone
// configures a domain once per process).
//
// Configuration: `cyclone_config` names a Cyclone XML file (deploy/cyclonedds-loopback.xml for
// loopback-only tests and demos) and is handed to dds_create_domain, so rsud's own file says which
// network it uses, without the environment. Empty: Cyclone's defaults, or the CYCLONEDDS_URI
// environment variable when set (the usual ROS 2 way).
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <string>

namespace rsu::dds {

struct ParticipantConfig {
  std::uint32_t domain_id = 0;  // ROS_DOMAIN_ID; DDS allows 0..232
  std::string cyclone_config;   // path of a Cyclone XML configuration file, or empty
};

class Participant {
 public:
  // Throws DdsError (Cyclone's text) or std::runtime_error (unreadable configuration file).
  explicit Participant(const ParticipantConfig& config);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  dds_entity_t handle() const { return participant_; }
  std::uint32_t domain_id() const { return domain_id_; }

 private:
  std::uint32_t domain_id_ = 0;
  dds_entity_t domain_ = 0;  // > 0 when this participant created the domain with its configuration
  dds_entity_t participant_ = 0;
};

}  // namespace rsu::dds
