// SPDX-License-Identifier: Apache-2.0
#include "dds/qos_config.h"

#include <cmath>

#include "io/yaml_field.h"

namespace rsu::dds {

QosPtr make_qos(const QosConfig& config) {
  QosPtr qos(dds_create_qos());
  const dds_duration_t blocking = static_cast<dds_duration_t>(std::llround(config.max_blocking_s * 1e9));
  if (config.reliability == Reliability::kReliable)
    dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, blocking);
  else
    dds_qset_reliability(qos.get(), DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_durability(qos.get(), config.durability == Durability::kTransientLocal
                                     ? DDS_DURABILITY_TRANSIENT_LOCAL
                                     : DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, static_cast<int32_t>(config.history_depth));
  const dds_data_representation_id_t xcdr1[] = {DDS_DATA_REPRESENTATION_XCDR1};
  dds_qset_data_representation(qos.get(), 1, xcdr1);
  return qos;
}

QosConfig read_qos_config(const io::YamlField& f, const QosConfig& defaults) {
  f.expect_map({"reliability", "durability", "history_depth", "max_blocking_s"});
  QosConfig q = defaults;
  if (f.has("reliability")) {
    const io::YamlField r = f.child("reliability");
    const std::string v = r.text();
    if (v == "reliable")
      q.reliability = Reliability::kReliable;
    else if (v == "best_effort")
      q.reliability = Reliability::kBestEffort;
    else
      r.fail("expected reliable or best_effort, got \"" + v + "\"");
  }
  if (f.has("durability")) {
    const io::YamlField d = f.child("durability");
    const std::string v = d.text();
    if (v == "volatile")
      q.durability = Durability::kVolatile;
    else if (v == "transient_local")
      q.durability = Durability::kTransientLocal;
    else
      d.fail("expected volatile or transient_local, got \"" + v + "\"");
  }
  if (f.has("history_depth")) {
    const io::YamlField h = f.child("history_depth");
    const double v = h.number();
    if (v < 1 || v > 10000 || v != std::floor(v))
      h.fail("must be a whole number within [1, 10000]");
    q.history_depth = static_cast<std::uint32_t>(v);
  }
  q.max_blocking_s = f.non_negative_or("max_blocking_s", q.max_blocking_s);
  if (q.max_blocking_s > 10)
    f.child("max_blocking_s").fail("must be <= 10 s");
  return q;
}

}  // namespace rsu::dds
