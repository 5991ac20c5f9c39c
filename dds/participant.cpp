// SPDX-License-Identifier: Apache-2.0
#include "dds/participant.h"

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "dds/dds_error.h"
#include "io/text_file.h"

namespace rsu::dds {

Participant::Participant(const ParticipantConfig& config) : domain_id_(config.domain_id) {
  if (config.domain_id > 232)
    throw std::runtime_error("dds: domain id " + std::to_string(config.domain_id) + " is outside [0, 232]");
  if (!config.cyclone_config.empty()) {
    // Cyclone would only log a parse failure of a missing file: say plainly which file is missing.
    if (!std::ifstream(config.cyclone_config))
      throw std::runtime_error("dds: cannot read the Cyclone configuration " + config.cyclone_config + ": " +
                               io::errno_text());
    const std::string uri = "file://" + std::filesystem::absolute(config.cyclone_config).string();
    const dds_entity_t domain = dds_create_domain(config.domain_id, uri.c_str());
    if (domain == DDS_RETCODE_PRECONDITION_NOT_MET) {
      // This process already has the domain (another participant made it): it keeps that one's setup.
    } else {
      domain_ = check_entity(
          domain, "creating domain " + std::to_string(config.domain_id) + " with " + config.cyclone_config);
    }
  }
  const dds_entity_t participant = dds_create_participant(config.domain_id, nullptr, nullptr);
  if (participant < 0) {
    if (domain_ > 0)
      dds_delete(domain_);
    throw DdsError("creating a participant in domain " + std::to_string(config.domain_id), participant);
  }
  participant_ = participant;
}

Participant::~Participant() {
  dds_delete(participant_);
  // The domain goes with its last participant (another Participant of this process may still use it).
  if (domain_ > 0 && dds_get_children(domain_, nullptr, 0) == 0)
    dds_delete(domain_);
}

}  // namespace rsu::dds
