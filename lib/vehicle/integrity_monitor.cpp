// SPDX-License-Identifier: Apache-2.0
#include "vehicle/integrity_monitor.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

#include "fusion/measurement_model.h"

namespace rsu::vehicle {
namespace {

// Wilson-Hilferty: the chi-square quantile of `dof` degrees of freedom at z standard deviations of the
// normal (within 1 % of the exact quantile for dof >= 10).
double chi_square_quantile(int dof, double z) {
  const double k = dof;
  const double a = 2.0 / (9.0 * k);
  return k * std::pow(1.0 - a + z * std::sqrt(a), 3);
}

// Normalized innovation squared, infinite when S is not positive definite.
double nis(const Eigen::Vector3d& r, const Eigen::Matrix3d& s) {
  const Eigen::LLT<Eigen::Matrix3d> llt(s);
  if (llt.info() != Eigen::Success) {
    return std::numeric_limits<double>::infinity();
  }
  const double d = r.dot(llt.solve(r));
  return d >= 0.0 ? d : std::numeric_limits<double>::infinity();
}

// Doubles per earlier exclusion (the first exclusion: x1), at most `cap`.
template <typename T>
T doubled(T base, int exclusions, T cap) {
  T value = base;
  for (int i = 1; i < exclusions && value < cap; ++i) {
    value *= 2;
  }
  return std::min(value, cap);
}

// The fix's innovation against `estimate` at its sweep time (x, y, box yaw), its covariance (both
// estimates') and its NIS.
struct FixInnovation {
  Eigen::Vector3d residual;
  Eigen::Matrix3d covariance;
  double nis;
};

FixInnovation fix_innovation(const v2i::Correction& fix, const fusion::StateEstimate& estimate,
                             const Eigen::Vector2d& reference_offset) {
  const fusion::PoseMeasurement m{fix.sweep_time, fusion::MeasurementSource::kRsu, fix.pose,
                                  fix.pose_covariance};
  const fusion::PoseInnovation innovation = fusion::pose_innovation(estimate.state, m, reference_offset);
  const auto& h = innovation.jacobian;
  const Eigen::Matrix3d covariance = h * estimate.covariance * h.transpose() + fix.pose_covariance;
  return {innovation.residual, covariance, nis(innovation.residual, covariance)};
}

}  // namespace

const char* to_string(SourceState state) {
  switch (state) {
    case SourceState::kProbation:
      return "probation";
    case SourceState::kAdmitted:
      return "admitted";
    case SourceState::kExcluded:
      return "excluded";
    case SourceState::kBarred:
      return "barred";
    case SourceState::kCount:
      break;
  }
  return "unknown";
}

const char* to_string(ExclusionReason reason) {
  switch (reason) {
    case ExclusionReason::kNone:
      return "none";
    case ExclusionReason::kGrossFixes:
      return "gross_fixes";
    case ExclusionReason::kCumulative:
      return "cumulative";
    case ExclusionReason::kCount:
      break;
  }
  return "unknown";
}

const char* to_string(FixVerdict verdict) {
  switch (verdict) {
    case FixVerdict::kUse:
      return "use";
    case FixVerdict::kUseOwnFailed:
      return "use_own_failed";
    case FixVerdict::kProbation:
      return "probation";
    case FixVerdict::kExcluded:
      return "excluded";
    case FixVerdict::kBarred:
      return "barred";
    case FixVerdict::kInconsistent:
      return "inconsistent";
    case FixVerdict::kCount:
      break;
  }
  return "unknown";
}

double fix_nis(const v2i::Correction& fix, const fusion::StateEstimate& estimate,
               const Eigen::Vector2d& reference_offset) {
  return fix_innovation(fix, estimate, reference_offset).nis;
}

FixCheck IntegrityMonitor::check(const v2i::Correction& fix, const fusion::StateEstimate& own,
                                 OwnEstimate status, const Eigen::Vector2d& reference_offset, bool on_track) {
  ++checks_;
  SourceRecord& s = record(fix.rsu_id);
  ++s.fixes;
  const TimeNs t = fix.sweep_time;
  const FixInnovation innovation = fix_innovation(fix, own, reference_offset);
  FixCheck out;
  out.nis = innovation.nis;
  if (s.state == SourceState::kAdmitted && !on_track) {
    s.track_broken = true;
  }
  s.last_time = t;
  s.last_innovation = innovation.residual;
  s.last_covariance = fix.pose_covariance;
  s.last_beyond_gate = !(out.nis <= config_.fix_gate_chi2);
  out.peers_agree_against_own = compare_with_peers(fix.rsu_id, s);
  totals_.peer_agreements_against_own += out.peers_agree_against_own ? 1 : 0;

  if (s.state == SourceState::kBarred) {
    out.verdict = FixVerdict::kBarred;
  } else if (status == OwnEstimate::kOverruled || out.peers_agree_against_own) {
    // The own estimate is no reference: nothing is held against a source for disagreeing with it.
    if (s.state == SourceState::kExcluded) {
      ++s.readmissions;
      ++totals_.readmissions;
    }
    if (s.state != SourceState::kAdmitted) {
      admit(s, out);
    }
    s.cusum = 0.0;
    s.run.clear();
    out.verdict = FixVerdict::kUseOwnFailed;
  } else {
    const bool correlated = status == OwnEstimate::kDegraded && s.state == SourceState::kAdmitted &&
                            !s.track_broken && agreed_over_run(s, innovation.covariance);
    update_cusum(s, out.nis, t, correlated);
    s.run.back().innovation = innovation.residual;
    admit_or_exclude(s, out.nis, t, out);
    if (s.state == SourceState::kAdmitted) {
      out.verdict = s.last_beyond_gate                 ? FixVerdict::kInconsistent
                    : status == OwnEstimate::kDegraded ? FixVerdict::kUseOwnFailed
                                                       : FixVerdict::kUse;
    } else {
      out.verdict = s.state == SourceState::kProbation  ? FixVerdict::kProbation
                    : s.state == SourceState::kExcluded ? FixVerdict::kExcluded
                                                        : FixVerdict::kBarred;
    }
  }
  s.verdicts.add(out.verdict);
  totals_.verdicts.add(out.verdict);
  return out;
}

void IntegrityMonitor::annul_exclusions_since(TimeNs since) {
  for (auto& [id, s] : sources_) {
    if (s.state != SourceState::kExcluded || s.excluded_at < since) {
      continue;
    }
    s.state = SourceState::kProbation;
    s.cusum = 0.0;
    s.run.clear();
    s.peer_agreements = 0;
    --s.exclusions;
    ++totals_.annulled;
  }
}

SourceRecord& IntegrityMonitor::record(std::uint64_t rsu_id) {
  auto it = sources_.find(rsu_id);
  if (it == sources_.end()) {
    if (sources_.size() >= std::max<std::size_t>(config_.max_sources, 1)) {
      sources_.erase(std::min_element(sources_.begin(), sources_.end(), [](const auto& a, const auto& b) {
        return a.second.last_heard < b.second.last_heard;
      }));
    }
    it = sources_.emplace(rsu_id, SourceRecord{}).first;
  }
  it->second.last_heard = checks_;
  return it->second;
}

// The own estimate's error is common to both innovations (up to its motion over the gap), so their
// difference compares the two RSUs' fixes directly. Updates the source's run of fixes that agreed with an
// admitted peer, and says whether a peer agrees with this fix while both disagree with the own estimate.
bool IntegrityMonitor::compare_with_peers(std::uint64_t rsu_id, SourceRecord& self) {
  bool agree_against_own = false;
  int admitted_agree = 0;
  int admitted_disagree = 0;
  for (const auto& [id, other] : sources_) {
    if (id == rsu_id || other.fixes == 0 ||
        std::abs(self.last_time - other.last_time) > config_.pair_max_gap) {
      continue;
    }
    const double motion =
        config_.pair_motion_sigma_mps * to_seconds(std::abs(self.last_time - other.last_time));
    Eigen::Matrix3d s = self.last_covariance + other.last_covariance;
    s(0, 0) += motion * motion;
    s(1, 1) += motion * motion;
    const bool consistent = nis(self.last_innovation - other.last_innovation, s) <= config_.pair_gate_chi2;
    ++totals_.pair_checks;
    totals_.pair_disagreements += consistent ? 0 : 1;
    agree_against_own = agree_against_own || (consistent && self.last_beyond_gate && other.last_beyond_gate);
    if (other.state == SourceState::kAdmitted) {
      (consistent ? admitted_agree : admitted_disagree) += 1;
    }
  }
  if (admitted_disagree > 0) {
    self.peer_agreements = 0;
  } else if (admitted_agree > 0) {
    ++self.peer_agreements;
  }
  return agree_against_own;
}

void IntegrityMonitor::update_cusum(SourceRecord& s, double nis, TimeNs t, bool correlated) const {
  // A fix counts at most cusum_cap, so that one gross fix alone never excludes a source; right after a
  // suspicious fix (the one before it, within max_fix_gap) it counts up to cusum_continuing_cap, so that
  // a gross one completes the exclusion: two bad fixes in a row, even where both covariances were wide
  // enough to keep the first one's NIS moderate. Not while excluded: there the CUSUM only paces
  // readmission.
  const bool after_suspicious = s.state != SourceState::kExcluded && !s.run.empty() &&
                                t - s.run.back().time <= config_.max_fix_gap &&
                                s.run.back().nis > config_.suspicious_fix_chi2;
  const double cap =
      after_suspicious ? std::max(config_.cusum_cap, config_.cusum_continuing_cap) : config_.cusum_cap;
  double step = std::min(nis, cap) - config_.cusum_drift;
  // Against a degraded own estimate, a fix of an admitted source still on its track, within the gate,
  // counts only for the time it adds, as a share of the correlation time of that estimate's error:
  // consecutive fixes there hold one error of the own estimate, not several
  // (IntegrityConfig::degraded_own_correlation_time). A gross fix counts in full.
  const bool continues_run =
      !s.run.empty() && t > s.run.back().time && t - s.run.back().time <= config_.max_fix_gap;
  if (correlated && nis <= config_.fix_gate_chi2 && continues_run &&
      config_.degraded_own_correlation_time > 0) {
    step *= std::min(1.0, static_cast<double>(t - s.run.back().time) /
                              static_cast<double>(config_.degraded_own_correlation_time));
  }
  if (s.cusum <= 0.0 && step > 0.0) {
    s.excursion_start = t;
  }
  s.cusum = std::max(0.0, s.cusum + step);
  if (!s.run.empty() && t - s.run.back().time > config_.max_fix_gap) {
    s.run.clear();  // a gap breaks the run of consecutive fixes
  }
  s.run.push_back({t, nis, Eigen::Vector3d::Zero()});
  while (s.run.size() > static_cast<std::size_t>(std::max(config_.max_admit_fixes, 1))) {
    s.run.pop_front();
  }
}

void IntegrityMonitor::admit_or_exclude(SourceRecord& s, double nis, TimeNs t, FixCheck& out) {
  if (s.state != SourceState::kExcluded && s.cusum > config_.cusum_threshold) {
    exclude(s, nis, t, out);
    return;
  }
  if (s.state == SourceState::kProbation) {
    // Consistent with the own estimate for a while, or with an admitted RSU (an independent check).
    if (admissible(s, config_.admit_after_fixes) || s.peer_agreements >= config_.peer_admit_after_fixes) {
      admit(s, out);
    }
  } else if (s.state == SourceState::kExcluded &&
             t - s.excluded_at >= doubled(config_.min_exclusion, s.exclusions, config_.max_exclusion) &&
             admissible(s, doubled(config_.admit_after_fixes, s.exclusions + 1, config_.max_admit_fixes))) {
    admit(s, out);
    ++s.readmissions;
    ++totals_.readmissions;
  }
}

bool IntegrityMonitor::agreed_over_run(const SourceRecord& s,
                                       const Eigen::Matrix3d& innovation_covariance) const {
  const TimeNs correlation = config_.degraded_own_correlation_time;
  if (s.run.empty() || correlation <= 0 || s.run.back().time - s.run.front().time < 3 * correlation) {
    return false;
  }
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const SourceRecord::RunFix& f : s.run) {
    mean += f.innovation;
  }
  mean /= static_cast<double>(s.run.size());
  const double independent_samples =
      static_cast<double>(s.run.back().time - s.run.front().time) / static_cast<double>(correlation);
  return nis(mean, innovation_covariance / independent_samples) <= config_.agreement_chi2;
}

bool IntegrityMonitor::admissible(const SourceRecord& s, int fixes_needed) const {
  const auto n = static_cast<std::size_t>(std::max(fixes_needed, 1));
  if (s.run.size() < n || s.cusum > 0.5 * config_.cusum_threshold) {
    return false;
  }
  double sum = 0.0;
  for (auto it = s.run.end() - static_cast<std::ptrdiff_t>(n); it != s.run.end(); ++it) {
    sum += it->nis;
  }
  return sum <= chi_square_quantile(3 * static_cast<int>(n), config_.admit_z);
}

void IntegrityMonitor::exclude(SourceRecord& s, double nis, TimeNs t, FixCheck& out) {
  ++s.exclusions;
  s.reason = nis <= config_.fix_gate_chi2 ? ExclusionReason::kCumulative : ExclusionReason::kGrossFixes;
  s.state = s.exclusions >= config_.max_exclusions ? SourceState::kBarred : SourceState::kExcluded;
  s.excluded_at = t;
  s.run.clear();  // readmission is earned by fixes after the exclusion
  const TimeNs latency = t - s.excursion_start;
  if (s.first_exclusion_latency < 0) {
    s.first_exclusion_latency = latency;
  }
  s.max_exclusion_latency = std::max(s.max_exclusion_latency, latency);
  totals_.max_exclusion_latency = std::max(totals_.max_exclusion_latency, latency);
  totals_.exclusions.add(s.reason);
  totals_.barred += s.state == SourceState::kBarred ? 1 : 0;
  out.excluded_now = true;
}

void IntegrityMonitor::admit(SourceRecord& s, FixCheck& out) {
  s.state = SourceState::kAdmitted;
  s.track_broken = false;
  out.admitted_now = true;
}

}  // namespace rsu::vehicle
