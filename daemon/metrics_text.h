// SPDX-License-Identifier: Apache-2.0
// rsud's counters, levels, measured values and histograms in the Prometheus text exposition format
// (version 0.0.4: "# HELP", "# TYPE", one sample per line), as node_exporter's textfile collector reads
// it. Names and help come from the one list every part reports into (common/counter_list.h): the stats
// file's "area.name" becomes rsud_area_name, counts get the suffix _total.
#pragma once

#include <span>
#include <string>
#include <string_view>

#include "common/counter_list.h"
#include "common/histogram.h"

namespace rsu::daemon {

struct NamedHistogram {
  std::string_view name;  // the metric's name without the prefix, e.g. "correction_latency_seconds"
  std::string_view help;
  const Histogram* histogram = nullptr;
};

// The metric name of a stats-file name: "rsud_" + the name with every character outside [A-Za-z0-9_]
// made '_' + "_total" for counts.
std::string metric_name(const Stat& stat);

std::string prometheus_text(const CounterList& stats, std::span<const NamedHistogram> histograms);

}  // namespace rsu::daemon
