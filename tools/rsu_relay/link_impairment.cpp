#include "tools/rsu_relay/link_impairment.h"

#include <algorithm>

#include "common/random.h"

namespace rsu::tools {
namespace {

// Uniform in (0, 1) for datagram `index` of `direction`, one independent stream per kind of draw.
double draw(std::uint64_t seed, std::uint64_t direction, std::uint64_t kind, std::uint64_t index) {
  return uniform_open01(mix64(seed ^ mix64((direction << 8 | kind) ^ mix64(index))));
}

}  // namespace

LinkDecision decide(const LinkImpairment& link, std::uint64_t seed, std::uint64_t direction,
                    std::uint64_t index) {
  LinkDecision out;
  out.drop = link.loss > 0.0 && draw(seed, direction, 1, index) < link.loss;
  out.hold_for_next = !out.drop && link.reorder > 0.0 && draw(seed, direction, 2, index) < link.reorder;
  const double jitter = link.jitter_ms * (2.0 * draw(seed, direction, 3, index) - 1.0);
  out.delay = from_seconds(std::max(0.0, link.delay_ms + jitter) * 1e-3);
  return out;
}

}  // namespace rsu::tools
