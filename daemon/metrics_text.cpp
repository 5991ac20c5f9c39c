// SPDX-License-Identifier: Apache-2.0
#include "daemon/metrics_text.h"

#include <charconv>
#include <cmath>

namespace rsu::daemon {
namespace {

constexpr std::string_view kPrefix = "rsud_";

std::string sanitized(std::string_view name) {
  std::string out(name);
  for (char& c : out) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok)
      c = '_';
  }
  return out;
}

// Shortest text that reads back as the same double; NaN and infinities as Prometheus spells them.
std::string number(double v) {
  if (std::isnan(v))
    return "NaN";
  if (std::isinf(v))
    return v > 0 ? "+Inf" : "-Inf";
  char buffer[64];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  return ec == std::errc() ? std::string(buffer, end) : "NaN";
}

void family(std::string& out, const std::string& name, std::string_view type, std::string_view help) {
  // HELP text escapes backslash and newline (the format's only escapes there).
  out += "# HELP " + name + " ";
  for (const char c : help) {
    if (c == '\\')
      out += "\\\\";
    else if (c == '\n')
      out += "\\n";
    else
      out += c;
  }
  out += "\n# TYPE " + name + " ";
  out += type;
  out += "\n";
}

std::string help_of(const Stat& s) {
  switch (s.kind) {
    case StatKind::kCount:
      return s.name + " in rsud's stats file: a count since rsud started";
    case StatKind::kLevel:
      return s.name + " in rsud's stats file: its current value";
    case StatKind::kMeasured:
      break;
  }
  return s.name + " in rsud's stats file: the latest measured value (NaN while unknown)";
}

}  // namespace

std::string metric_name(const Stat& stat) {
  return std::string(kPrefix) + sanitized(stat.name) + (stat.kind == StatKind::kCount ? "_total" : "");
}

std::string prometheus_text(const CounterList& stats, std::span<const NamedHistogram> histograms) {
  std::string out;
  for (const Stat& s : stats.stats()) {
    const std::string name = metric_name(s);
    family(out, name, s.kind == StatKind::kCount ? "counter" : "gauge", help_of(s));
    out += name + " " + (s.kind == StatKind::kMeasured ? number(s.measured) : std::to_string(s.count)) + "\n";
  }
  for (const NamedHistogram& h : histograms) {
    const std::string name = std::string(kPrefix) + sanitized(h.name);
    family(out, name, "histogram", h.help);
    const std::vector<double>& bounds = h.histogram->upper_bounds();
    for (std::size_t i = 0; i <= bounds.size(); ++i) {
      out += name + "_bucket{le=\"" + (i < bounds.size() ? number(bounds[i]) : "+Inf") + "\"} " +
             std::to_string(h.histogram->cumulative(i)) + "\n";
    }
    out += name + "_sum " + number(h.histogram->sum()) + "\n";
    out += name + "_count " + std::to_string(h.histogram->count()) + "\n";
  }
  return out;
}

}  // namespace rsu::daemon
