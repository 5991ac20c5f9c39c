// SPDX-License-Identifier: Apache-2.0
// The QoS a topic's reader or writer is made with: a plain struct with this project's defaults, read
// from YAML (rsud.yaml's `dds:` section) and turned into Cyclone QoS. Deadline and liveliness are
// left at DDS's defaults (infinite): a LiDAR or a vehicle going quiet is not a DDS error here.
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <memory>

namespace rsu::io {
class YamlField;
}

namespace rsu::dds {

enum class Reliability : std::uint8_t { kReliable, kBestEffort };
enum class Durability : std::uint8_t { kVolatile, kTransientLocal };

struct QosConfig {
  // Reliable by default: a best-effort reader loses a whole fragmented sample (a ~1 MB PointCloud2
  // is ~800 fragments) to one lost fragment (docs/design.md §5). ROS 2's sensor-data profile is best
  // effort: set it so to match such publishers (a reliable reader never matches a best-effort writer).
  Reliability reliability = Reliability::kReliable;
  Durability durability = Durability::kVolatile;
  // KEEP_LAST depth: how many samples wait when the reader falls behind; older ones are dropped.
  std::uint32_t history_depth = 2;
  // How long a reliable writer may block when readers lag before dds_write gives up (timeout).
  double max_blocking_s = 0.1;
};

struct QosDeleter {
  void operator()(dds_qos_t* q) const { dds_delete_qos(q); }
};
using QosPtr = std::unique_ptr<dds_qos_t, QosDeleter>;

// Cyclone QoS for `config`, with XCDR1 as the only data representation (ROS 2 speaks XCDR1 only,
// docs/design.md §5).
QosPtr make_qos(const QosConfig& config);

// Reads {reliability: reliable|best_effort, durability: volatile|transient_local, history_depth: N,
// max_blocking_s: S}; absent keys keep `defaults`. Throws io::YamlError naming file, line and field.
QosConfig read_qos_config(const io::YamlField& field, const QosConfig& defaults);

}  // namespace rsu::dds
