// SPDX-License-Identifier: Apache-2.0
// Fault detection and exclusion of RSU sources on the vehicle (as GNSS receivers do for satellites with
// RAIM): every fix of every RSU is checked against the vehicle's own estimate (its NDT-only filter at
// the fix's sweep time) with both covariances, and against the other RSUs' fixes where there are
// several. A source whose fixes disagree beyond what the covariances allow, one gross fix after another
// or a run of moderately wrong ones (a CUSUM on the normalized innovations), is excluded, with a reason,
// and counted; it is readmitted only after a run of consistent fixes that grows with each exclusion.
// A new source is fused only once its first fixes were consistent. When the vehicle's own estimate is
// known to have failed, it is a weaker reference (its NDT says so: its covariance is inflated, and sources
// are judged against that) or none at all (two RSUs agree against it).
// Pure computation.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <map>
#include <utility>

#include "common/enum_counter.h"
#include "common/time.h"
#include "fusion/vehicle_ekf.h"
#include "v2i/messages.h"
#include "vehicle/integrity_config.h"

namespace rsu::vehicle {

enum class SourceState : std::uint8_t {
  kProbation,  // new: checked, not fused until its fixes were consistent for a while
  kAdmitted,   // fused (fix by fix, within the per-fix gate)
  kExcluded,   // checked, not fused, until readmitted
  kBarred,     // excluded too often: not used again this trip
  kCount,
};

enum class ExclusionReason : std::uint8_t {
  kNone,
  kGrossFixes,  // the CUSUM tripped on fixes beyond the per-fix gate (gross errors)
  kCumulative,  // ... on a run of fixes each within the gate but together too far off
  kCount,
};

// What the vehicle knows about its own estimate at a fix's sweep time.
enum class OwnEstimate : std::uint8_t {
  kHealthy,    // the reference every source is judged against
  kDegraded,   // its NDT says the match failed: a weaker reference (inflated covariance), judged
               // against as ever; what passes may re-anchor the fused filter
  kOverruled,  // two RSUs agreed against it: no reference at all
};

enum class FixVerdict : std::uint8_t {
  kUse,           // admitted source, fix consistent with the own estimate: fuse it
  kUseOwnFailed,  // the own estimate has failed (degraded or overruled): fuse it (the fused filter
                  // may re-anchor at it)
  kProbation,     // source not admitted yet
  kExcluded,      // source excluded
  kBarred,        // source barred
  kInconsistent,  // admitted source, but this fix is beyond the per-fix gate
  kCount,
};

const char* to_string(SourceState state);
const char* to_string(ExclusionReason reason);
const char* to_string(FixVerdict verdict);

struct FixCheck {
  FixVerdict verdict = FixVerdict::kProbation;
  double nis = 0.0;                      // against the own estimate (3 dof)
  bool peers_agree_against_own = false;  // another RSU agrees with this fix, both disagree with own
  bool excluded_now = false;             // this fix excluded its source
  bool admitted_now = false;             // this fix admitted (or readmitted) its source

  bool use() const { return verdict == FixVerdict::kUse || verdict == FixVerdict::kUseOwnFailed; }
};

// Everything known about one RSU (by rsu_id).
struct SourceRecord {
  SourceState state = SourceState::kProbation;
  ExclusionReason reason = ExclusionReason::kNone;  // of the latest exclusion
  double cusum = 0.0;
  TimeNs excursion_start = 0;  // sweep time of the first fix of the CUSUM's current rise
  TimeNs excluded_at = 0;      // sweep time of the fix that excluded it
  int exclusions = 0;
  struct RunFix {
    TimeNs time = 0;  // sweep time
    double nis = 0.0;
    Eigen::Vector3d innovation = Eigen::Vector3d::Zero();  // against the own estimate
  };
  std::deque<RunFix> run;  // the latest consecutive fixes

  // The latest fix, for the comparison between RSUs.
  TimeNs last_time = 0;
  Eigen::Vector3d last_innovation = Eigen::Vector3d::Zero();
  Eigen::Matrix3d last_covariance = Eigen::Matrix3d::Identity();
  bool last_beyond_gate = false;
  // Since its latest admission a fix of it did not fit the fused filter's track (check's on_track): it
  // jumped, and its fixes count in full against a degraded own estimate.
  bool track_broken = false;
  int peer_agreements = 0;       // its latest fixes in a row that agreed with every admitted RSU compared
  std::uint64_t last_heard = 0;  // check() count, for least-recently-heard eviction

  std::uint64_t fixes = 0;
  EnumCounter<FixVerdict> verdicts;
  std::uint64_t readmissions = 0;
  TimeNs first_exclusion_latency = -1;  // first fix of the excursion -> exclusion, -1: never excluded
  TimeNs max_exclusion_latency = -1;
};

struct IntegrityTotals {
  EnumCounter<FixVerdict> verdicts;
  EnumCounter<ExclusionReason> exclusions;
  std::uint64_t readmissions = 0;
  std::uint64_t annulled = 0;  // exclusions annulled: decided against an own estimate found failing
  std::uint64_t barred = 0;
  std::uint64_t pair_checks = 0;         // fixes of two RSUs compared
  std::uint64_t pair_disagreements = 0;  // ... that disagreed
  std::uint64_t peer_agreements_against_own = 0;
  TimeNs max_exclusion_latency = -1;
};

// The normalized innovation squared (3 dof: x, y, box yaw) of `fix` against `estimate` at its sweep
// time, with both covariances (infinite when their sum is not positive definite).
double fix_nis(const v2i::Correction& fix, const fusion::StateEstimate& estimate,
               const Eigen::Vector2d& reference_offset);

class IntegrityMonitor {
 public:
  explicit IntegrityMonitor(const IntegrityConfig& config = {}) : config_(config) {}

  // Checks one fix against `own` (the own estimate at the fix's sweep time) whose standing is `status`.
  // `reference_offset`: the announced reference point minus the box centre (the fix gives the centre).
  // `on_track`: the fix fits the fused filter's estimate at its sweep (fix_fits), which this source's
  // earlier fixes led: its own track did not jump. Only such fixes of an admitted source that never
  // jumped are counted as correlated evidence against a degraded own estimate
  // (IntegrityConfig::degraded_own_correlation_time).
  FixCheck check(const v2i::Correction& fix, const fusion::StateEstimate& own, OwnEstimate status,
                 const Eigen::Vector2d& reference_offset, bool on_track = false);

  // The own estimate turns out to have been failing since `since` (its NDT has just said so, and may have
  // been failing before it did): exclusions decided against it from then on are annulled, the sources go
  // back to probation with their CUSUM cleared. Counted.
  void annul_exclusions_since(TimeNs since);

  const std::map<std::uint64_t, SourceRecord>& sources() const { return sources_; }
  const IntegrityTotals& totals() const { return totals_; }
  const IntegrityConfig& config() const { return config_; }

 private:
  SourceRecord& record(std::uint64_t rsu_id);
  bool compare_with_peers(std::uint64_t rsu_id, SourceRecord& self);
  void update_cusum(SourceRecord& s, double nis, TimeNs t, bool correlated) const;
  // The source's run of fixes spans at least three correlation times of a degraded own estimate's error,
  // and their mean innovation is within that estimate's covariance `s` shrunk by the independent samples
  // it holds (chi-square 95 %, 3 dof): it has agreed with the own estimate on average, not only now.
  bool agreed_over_run(const SourceRecord& s, const Eigen::Matrix3d& innovation_covariance) const;
  void admit_or_exclude(SourceRecord& s, double nis, TimeNs t, FixCheck& out);
  bool admissible(const SourceRecord& s, int fixes_needed) const;
  void exclude(SourceRecord& s, double nis, TimeNs t, FixCheck& out);
  void admit(SourceRecord& s, FixCheck& out);

  IntegrityConfig config_;
  std::map<std::uint64_t, SourceRecord> sources_;
  IntegrityTotals totals_;
  std::uint64_t checks_ = 0;
};

}  // namespace rsu::vehicle
