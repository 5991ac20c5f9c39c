// SPDX-License-Identifier: Apache-2.0
// The vehicle's V2I client: announces the vehicle (size, own pose, where to reply) to the RSUs over UDP
// and receives their corrections, delivered by callback and by poll(). Boost.Asio at the edge; what to
// send and which corrections to take are decided by lib/vehicle (Announcer, CorrectionFilter). Runs on
// an io_context the caller owns (ThreadedVehicleClient runs its own thread). All public methods are
// thread-safe; the callback runs on the io_context's thread.
#pragma once

#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange under C++20

#include <Eigen/Core>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/enum_counter.h"
#include "common/pose.h"
#include "common/time.h"
#include "v2i/announcement_validation.h"
#include "v2i/messages.h"
#include "vehicle/announcer.h"
#include "vehicle/correction_filter.h"
#include "vehicle_client/clock.h"
#include "vehicle_client/vehicle_client_config.h"

namespace rsu::vehicle_client {

using vehicle::CorrectionVerdict;
using vehicle::VehicleState;

struct ReceivedCorrection {
  v2i::Correction correction;
  TimeNs received_time = 0;  // client clock
  std::string sender;        // "ADDR:PORT" of the datagram's source
};

// An RSU's notice that it refused one of this vehicle's announcements (proto/v2i.proto
// AnnouncementRefusal), authenticated like a correction.
struct ReceivedRefusal {
  v2i::AnnouncementRefusal refusal;
  TimeNs received_time = 0;  // client clock
  std::string sender;        // "ADDR:PORT" of the datagram's source
};

// An RSU's advertisement (proto/v2i.proto RsuAdvertisement), authenticated like a correction: it says
// whether that RSU withholds its fixes now, and why.
struct ReceivedAdvertisement {
  v2i::RsuAdvertisement advertisement;
  TimeNs received_time = 0;  // client clock
  std::string sender;        // "ADDR:PORT" of the datagram's source
};

// An RSU's notice that it swept this vehicle and sends it no correction for that rotation, and why
// (proto/v2i.proto FixWithheld), authenticated like a correction.
struct ReceivedFixWithheld {
  v2i::FixWithheld notice;
  TimeNs received_time = 0;  // client clock
  std::string sender;        // "ADDR:PORT" of the datagram's source
};

struct VehicleClientStats {
  std::uint64_t announcements_sent = 0;  // datagrams, one per RSU per announcement
  std::uint64_t keepalive_announcements = 0;
  std::uint64_t send_errors = 0;
  std::uint64_t announcements_refused = 0;  // announce() refused the state (see announce())
  std::uint64_t datagrams_received = 0;
  std::uint64_t receive_errors = 0;
  // accepted, rejected by reason, and the RSUs' other messages (notices, advertisements)
  EnumCounter<CorrectionVerdict> corrections;
  EnumCounter<v2i::RefusalReason> refusals;  // refusal notices received, by the RSU's reason
  std::optional<ReceivedRefusal> last_refusal;
  // Advertisements received, by what they say about the fixes (none: corrections are sent).
  EnumCounter<v2i::FixesWithheld> advertisements;
  std::optional<ReceivedAdvertisement> last_advertisement;
  // Fixes an RSU withheld and said so (FixWithheld notices), by its reason.
  EnumCounter<v2i::FixWithheldReason> fixes_withheld;
  std::optional<ReceivedFixWithheld> last_fix_withheld;
  EnumCounter<v2i::AuthVerdict> authentication;  // every datagram's signature/replay verdict
  std::uint64_t sequence_restarts = 0;           // an RSU restarted (CorrectionFilter)
  std::uint64_t dropped_unpolled = 0;            // over max_pending_corrections

  std::uint64_t accepted() const { return corrections.count(CorrectionVerdict::kAccepted); }
  // Datagrams refused as corrections, not counting the RSUs' other messages it took (notices,
  // advertisements).
  std::uint64_t rejected() const {
    return corrections.total() - accepted() - corrections.count(CorrectionVerdict::kRefusal) -
           corrections.count(CorrectionVerdict::kAdvertisement) -
           corrections.count(CorrectionVerdict::kFixWithheld);
  }
};

class VehicleClient {
 public:
  using CorrectionCallback = std::function<void(const ReceivedCorrection&)>;

  // Opens and binds the socket and starts receiving. Throws std::invalid_argument for a bad config
  // (no RSU, vehicle id 0, unparsable endpoint, mixed address families, signed mode without a key)
  // and boost::system::system_error when the socket cannot be bound.
  VehicleClient(boost::asio::io_context& io, const VehicleClientConfig& config,
                Clock clock = edge::host_now_ns);
  ~VehicleClient();  // stops; the callback is not called after it returns
  VehicleClient(const VehicleClient&) = delete;
  VehicleClient& operator=(const VehicleClient&) = delete;

  // Announces the state to every RSU now (the send runs on the io_context) and keeps it for the
  // keep-alive. Returns kValid when queued; otherwise the reason the announcement would be refused by
  // an RSU (NaN, bad covariance, absurd size, ...), and nothing is sent. The generation time is not
  // checked against the clock: the RSU judges age. After stop() it sends nothing and returns kValid.
  v2i::AnnouncementReason announce(const VehicleState& state);

  // Corrections accepted since the last call, oldest first.
  std::vector<ReceivedCorrection> poll();
  // Also called for every accepted correction (in addition to poll()).
  void set_correction_callback(CorrectionCallback callback);

  VehicleClientStats stats() const;
  // The bound correction endpoint (the port is the real one when 0 was configured).
  boost::asio::ip::udp::endpoint local_endpoint() const;
  // The announcement endpoints, resolved.
  const std::vector<boost::asio::ip::udp::endpoint>& rsu_endpoints() const;
  // Sequence number the next announcement will carry.
  std::uint32_t next_sequence() const;

  // Stops receiving and announcing (idempotent). Pending handlers finish on the io_context.
  void stop();

 private:
  class Impl;
  std::shared_ptr<Impl> impl_;
};

// A VehicleClient with its own io_context and thread, for callers without an event loop (the CLI).
class ThreadedVehicleClient {
 public:
  explicit ThreadedVehicleClient(const VehicleClientConfig& config, Clock clock = edge::host_now_ns);
  ~ThreadedVehicleClient();
  ThreadedVehicleClient(const ThreadedVehicleClient&) = delete;
  ThreadedVehicleClient& operator=(const ThreadedVehicleClient&) = delete;

  VehicleClient& client() { return *client_; }
  const VehicleClient& client() const { return *client_; }

 private:
  struct Loop;
  std::unique_ptr<Loop> loop_;
  std::unique_ptr<VehicleClient> client_;
};

}  // namespace rsu::vehicle_client
