// SPDX-License-Identifier: Apache-2.0
#include "vehicle_client/cli/stats_report.h"

#include <fstream>
#include <stdexcept>

#include "io/text_file.h"

namespace rsu::vehicle_client::cli {
namespace {

unsigned long long ull(std::uint64_t v) {
  return static_cast<unsigned long long>(v);
}

double ms(TimeNs t) {
  return t < 0 ? -1.0 : static_cast<double>(t) * 1e-6;
}

template <typename Enum, typename Write>
void for_each_count(const EnumCounter<Enum>& counts, std::size_t first, Write write) {
  for (std::size_t i = first; i < static_cast<std::size_t>(Enum::kCount); ++i) {
    const auto e = static_cast<Enum>(i);
    if (counts.count(e) > 0) {
      write(e, counts.count(e));
    }
  }
}

}  // namespace

std::string describe(const v2i::FixWithheld& n) {
  std::string out = v2i::to_string(n.reason);
  char detail[96];
  if (n.position_sigma_m && n.max_position_sigma_m) {
    std::snprintf(detail, sizeof detail, " (sigma %.3f m, at most %.3f m)", *n.position_sigma_m,
                  *n.max_position_sigma_m);
    out += detail;
  }
  if (n.reason == v2i::FixWithheldReason::kMount)
    out += std::string(" (") + v2i::to_string(n.mount_cause) + ")";
  if (n.packets_lost_nearby)
    out += ", packets lost nearby";
  return out;
}

void print_summary(std::FILE* out, const VehicleClientStats& c, const vehicle::VehicleCore& core,
                   v2i::SecurityMode mode) {
  std::fprintf(out,
               "rsu-vehicle: announcements sent %llu (keep-alive %llu, send errors %llu, refused %llu); "
               "datagrams received %llu; corrections accepted %llu, rejected %llu",
               ull(c.announcements_sent), ull(c.keepalive_announcements), ull(c.send_errors),
               ull(c.announcements_refused), ull(c.datagrams_received), ull(c.accepted()), ull(c.rejected()));
  for_each_count(c.corrections, 1, [&](CorrectionVerdict v, std::uint64_t n) {
    std::fprintf(out, " %s=%llu", vehicle::to_string(v), ull(n));
  });
  if (c.refusals.total() > 0) {
    std::fprintf(out, "; announcements refused by RSUs");
    for_each_count(c.refusals, 0, [&](v2i::RefusalReason r, std::uint64_t n) {
      std::fprintf(out, " %s=%llu", v2i::to_string(r), ull(n));
    });
    if (c.last_refusal) {
      std::fprintf(out, " (latest: RSU %llu, %s: %s)", ull(c.last_refusal->refusal.rsu_id),
                   v2i::to_string(c.last_refusal->refusal.reason), c.last_refusal->refusal.detail.c_str());
    }
  }
  if (c.fixes_withheld.total() > 0) {
    std::fprintf(out, "; fixes withheld by RSUs");
    for_each_count(c.fixes_withheld, 0, [&](v2i::FixWithheldReason r, std::uint64_t n) {
      std::fprintf(out, " %s=%llu", v2i::to_string(r), ull(n));
    });
    if (c.last_fix_withheld) {
      std::fprintf(out, " (latest: RSU %llu, %s)", ull(c.last_fix_withheld->notice.rsu_id),
                   describe(c.last_fix_withheld->notice).c_str());
    }
  }
  if (c.advertisements.total() > 0) {
    std::fprintf(out, "; RSU advertisements, fixes withheld:");
    for_each_count(c.advertisements, 0, [&](v2i::FixesWithheld w, std::uint64_t n) {
      std::fprintf(out, " %s=%llu", v2i::to_string(w), ull(n));
    });
  }
  std::fprintf(out, "; authentication (%s)", v2i::to_string(mode));
  for_each_count(c.authentication, 0, [&](v2i::AuthVerdict v, std::uint64_t n) {
    std::fprintf(out, " %s=%llu", v2i::to_string(v), ull(n));
  });
  const vehicle::PoseFuserStats f = core.fuser_stats();
  std::fprintf(
      out,
      "; fuser: NDT accepted %llu rejected %llu, RSU accepted %llu rejected gate %llu yaw-branch %llu "
      "other %llu, late %llu, re-applied %llu, re-anchored at RSU fixes %llu, restarted at NDT %llu",
      ull(f.ndt_accepted), ull(f.ndt_rejected), ull(f.rsu_accepted), ull(f.rsu_rejected_gate),
      ull(f.rsu_rejected_yaw_branch), ull(f.rsu_rejected_other), ull(f.late), ull(f.reapplied),
      ull(f.rsu_reanchors), ull(f.ndt_restarts));
  const vehicle::IntegrityTotals& t = core.integrity().totals();
  std::fprintf(out, "; NDT poses %llu (degraded %llu, weakened in the fused filter %llu); integrity:",
               ull(core.stats().ndt_poses), ull(core.stats().ndt_degraded),
               ull(core.stats().ndt_weakened_in_fused));
  for_each_count(t.verdicts, 0, [&](vehicle::FixVerdict v, std::uint64_t n) {
    std::fprintf(out, " %s=%llu", vehicle::to_string(v), ull(n));
  });
  for (const auto& [id, s] : core.integrity().sources()) {
    std::fprintf(out, "; RSU %llu %s: %llu fixes, %d exclusions", ull(id), vehicle::to_string(s.state),
                 ull(s.fixes), s.exclusions);
    if (s.exclusions > 0) {
      std::fprintf(out, " (latest %s; the first %.0f ms after its first inconsistent fix), %llu readmissions",
                   vehicle::to_string(s.reason), ms(s.first_exclusion_latency), ull(s.readmissions));
    }
  }
  std::fprintf(out, "\n");
}

void write_stats_file(const std::string& path, const VehicleClientStats& c,
                      const vehicle::VehicleCore& core) {
  std::ofstream out(path);
  if (!out) {
    throw std::runtime_error("--stats: " + path + ": cannot open: " + io::errno_text());
  }
  out << "announcements.sent " << c.announcements_sent << "\ncorrections.accepted " << c.accepted()
      << "\ncorrections.rejected " << c.rejected() << "\n";
  // Announcements the RSUs refused and told the vehicle about (refusal notices), by their reason.
  for (std::size_t i = 1; i < static_cast<std::size_t>(v2i::RefusalReason::kCount); ++i) {
    const auto r = static_cast<v2i::RefusalReason>(i);
    out << "refusal." << v2i::to_string(r) << ' ' << c.refusals.count(r) << "\n";
  }
  if (c.last_refusal) {
    out << "refusal.last " << v2i::to_string(c.last_refusal->refusal.reason) << ':'
        << c.last_refusal->refusal.detail << "\n";
  }
  // Fixes the RSUs withheld and told the vehicle about (FixWithheld notices), by their reason
  // (unspecified: a reason this client does not know).
  for (std::size_t i = 0; i < static_cast<std::size_t>(v2i::FixWithheldReason::kCount); ++i) {
    const auto r = static_cast<v2i::FixWithheldReason>(i);
    out << "fix_withheld." << v2i::to_string(r) << ' ' << c.fixes_withheld.count(r) << "\n";
  }
  // The latest notice, one value per key like every line of the file ("key value": tools split on the
  // space): its reason, and the sigma the fix would have stated beside the largest sent, when given.
  if (c.last_fix_withheld) {
    const v2i::FixWithheld& n = c.last_fix_withheld->notice;
    out << "fix_withheld.last " << v2i::to_string(n.reason) << "\n";
    if (n.position_sigma_m && n.max_position_sigma_m) {
      out << "fix_withheld.last_sigma_m " << *n.position_sigma_m << "\nfix_withheld.last_max_sigma_m "
          << *n.max_position_sigma_m << "\n";
    }
  }
  // RSU advertisements received, by what they said about the fixes (none: sent).
  for (std::size_t i = 0; i < static_cast<std::size_t>(v2i::FixesWithheld::kCount); ++i) {
    const auto w = static_cast<v2i::FixesWithheld>(i);
    out << "advertisement.fixes_withheld." << v2i::to_string(w) << ' ' << c.advertisements.count(w) << "\n";
  }
  const vehicle::PoseFuserStats f = core.fuser_stats();
  out << "fuser.ndt_accepted " << f.ndt_accepted << "\nfuser.ndt_rejected " << f.ndt_rejected
      << "\nfuser.rsu_accepted " << f.rsu_accepted << "\nfuser.rsu_rejected_gate " << f.rsu_rejected_gate
      << "\nfuser.rsu_rejected_yaw_branch " << f.rsu_rejected_yaw_branch << "\nfuser.rsu_reanchors "
      << f.rsu_reanchors << "\nfuser.ndt_restarts " << f.ndt_restarts << "\n";
  out << "ndt.poses " << core.stats().ndt_poses << "\nndt.degraded " << core.stats().ndt_degraded
      << "\nndt.weakened_in_fused " << core.stats().ndt_weakened_in_fused << "\nndt.weakened_along_axis "
      << core.stats().ndt_weakened_along_axis << "\nndt.weakened_late " << core.stats().ndt_weakened_late
      << "\nintegrity.fixes_own_failed " << core.stats().fixes_own_failed << "\nfixes.coarse_not_fused "
      << core.stats().fixes_coarse_not_fused << "\n";
  const vehicle::IntegrityTotals& t = core.integrity().totals();
  for (std::size_t i = 0; i < static_cast<std::size_t>(vehicle::FixVerdict::kCount); ++i) {
    const auto v = static_cast<vehicle::FixVerdict>(i);
    out << "integrity.verdict." << vehicle::to_string(v) << ' ' << t.verdicts.count(v) << "\n";
  }
  for (std::size_t i = 1; i < static_cast<std::size_t>(vehicle::ExclusionReason::kCount); ++i) {
    const auto r = static_cast<vehicle::ExclusionReason>(i);
    out << "integrity.exclusions." << vehicle::to_string(r) << ' ' << t.exclusions.count(r) << "\n";
  }
  out << "integrity.readmissions " << t.readmissions << "\nintegrity.barred " << t.barred
      << "\nintegrity.pair_checks " << t.pair_checks << "\nintegrity.pair_disagreements "
      << t.pair_disagreements << "\nintegrity.peer_agreements_against_own " << t.peer_agreements_against_own
      << "\nintegrity.max_exclusion_latency_ms " << ms(t.max_exclusion_latency) << "\n";
  for (const auto& [id, s] : core.integrity().sources()) {
    const std::string key = "integrity.rsu." + std::to_string(id) + ".";
    out << key << "state " << vehicle::to_string(s.state) << "\n"
        << key << "fixes " << s.fixes << "\n"
        << key << "used "
        << s.verdicts.count(vehicle::FixVerdict::kUse) + s.verdicts.count(vehicle::FixVerdict::kUseOwnFailed)
        << "\n"
        << key << "exclusions " << s.exclusions << "\n"
        << key << "reason " << vehicle::to_string(s.reason) << "\n"
        << key << "first_exclusion_latency_ms " << ms(s.first_exclusion_latency) << "\n"
        << key << "max_exclusion_latency_ms " << ms(s.max_exclusion_latency) << "\n"
        << key << "readmissions " << s.readmissions << "\n";
  }
}

std::string integrity_event(const v2i::Correction& fix, const vehicle::FixCheck& check,
                            const vehicle::IntegrityMonitor& monitor) {
  if (!check.excluded_now && !check.admitted_now) {
    return {};
  }
  const auto it = monitor.sources().find(fix.rsu_id);
  if (it == monitor.sources().end()) {
    return {};
  }
  const vehicle::SourceRecord& s = it->second;
  char line[256];
  if (check.excluded_now) {
    std::snprintf(line, sizeof line,
                  "RSU %llu %s (%s, exclusion %d) at sweep %lld: %.0f ms after the first of its inconsistent "
                  "fixes (NIS %.1f)",
                  ull(fix.rsu_id), vehicle::to_string(s.state), vehicle::to_string(s.reason), s.exclusions,
                  static_cast<long long>(fix.sweep_time), ms(fix.sweep_time - s.excursion_start), check.nis);
  } else {
    std::snprintf(line, sizeof line, "RSU %llu admitted at sweep %lld after %llu fixes (%llu readmissions)",
                  ull(fix.rsu_id), static_cast<long long>(fix.sweep_time), ull(s.fixes), ull(s.readmissions));
  }
  return line;
}

}  // namespace rsu::vehicle_client::cli
