#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""rsud's Prometheus metrics (issue 14 item 4): the real rsud fed by the real `rsu-sim stream` and
`rsu-fleet` (scenarios/fault_street.yaml, a VLP-16, a connected car driving past), its node_exporter textfile
read while it serves the car and again after it stopped, each time parsed by this file's own reader of the
text exposition format (version 0.0.4), which checks:

  - every sample belongs to a family declared once, HELP then TYPE before its samples; names are valid
    metric names; counters end in _total;
  - histograms: buckets by ascending `le`, cumulative counts that never decrease, the +Inf bucket equal to
    _count, a _sum;
  - every value in rsud's stats file is there under its derived name with the same value (counts and
    levels; at exit both files describe the same moment), with a HELP line naming it;
  - the correction-latency histogram counts every correction sent, and its mean lies at most 20 ms below the
    mean delay the fleet measured independently (its receive time minus the correction's sweep time: the
    same delay plus the loopback hop and the fleet's reading, slow on a busy machine);
  - the sensor-clock-offset histogram saw every data packet, all within [-10 ms, 100 ms] (the stream shares
    the host's clock, so the offset is the loopback transit);
  - the LiDAR-step histogram saw at least every packet the decoder accepted.

A scrape mid-run must already show corrections. Every wait is bounded; children are killed on the way out.
"""
import argparse
import math
import os
import re
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from live_rsu import finish, run_case  # noqa: E402

SCENARIO = os.path.join(os.path.dirname(os.path.abspath(__file__)), "scenarios", "fault_street.yaml")
NAME = re.compile(r"^[a-zA-Z_:][a-zA-Z0-9_:]*$")
SAMPLE = re.compile(r'^([a-zA-Z_:][a-zA-Z0-9_:]*)(?:\{([^}]*)\})? (\S+)$')
LABEL = re.compile(r'^([a-zA-Z_][a-zA-Z0-9_]*)="((?:[^"\\]|\\.)*)"$')


def parse_value(text):
    if text in ("NaN", "+Inf", "-Inf"):
        return float(text.replace("Inf", "inf").replace("NaN", "nan"))
    return float(text)  # raises on anything else


def parse_exposition(text):
    """{family: {"type", "help", "samples": [(name, labels, value)]}}; raises AssertionError on any
    violation of the format."""
    families, current = {}, None
    assert text.endswith("\n"), "the exposition must end with a newline"
    for number, line in enumerate(text.split("\n")[:-1], 1):
        where = "line %d: %r" % (number, line)
        if line.startswith("# HELP "):
            name, _, help_text = line[7:].partition(" ")
            assert NAME.match(name), where
            assert name not in families, "family declared twice: " + where
            families[name] = {"help": help_text, "type": None, "samples": []}
            current = name
        elif line.startswith("# TYPE "):
            name, _, kind = line[7:].partition(" ")
            assert name == current and families[name]["type"] is None, "TYPE not right after its HELP: " + where
            assert kind in ("counter", "gauge", "histogram", "summary", "untyped"), where
            families[name]["type"] = kind
        else:
            assert not line.startswith("#") and line, where
            m = SAMPLE.match(line)
            assert m, "not a sample: " + where
            name, labels_text, value = m.group(1), m.group(2), parse_value(m.group(3))
            labels = {}
            for pair in filter(None, (labels_text or "").split(",")):
                lm = LABEL.match(pair)
                assert lm, "bad label: " + where
                labels[lm.group(1)] = lm.group(2)
            family = families.get(current)
            assert family is not None and family["type"] is not None, "sample before HELP/TYPE: " + where
            if family["type"] == "histogram":
                assert name in (current + "_bucket", current + "_sum", current + "_count"), where
            else:
                assert name == current and not labels, "sample outside its family: " + where
            if family["type"] == "counter":
                assert name.endswith("_total") and value >= 0, where
            family["samples"].append((name, labels, value))
    for name, f in families.items():
        assert f["samples"], "family without samples: " + name
        if f["type"] == "histogram":
            check_histogram(name, f)
        else:
            assert len(f["samples"]) == 1, name
    return families


def check_histogram(name, family):
    buckets = [(parse_value(l["le"]), v) for n, l, v in family["samples"] if n == name + "_bucket"]
    sums = [v for n, _, v in family["samples"] if n == name + "_sum"]
    counts = [v for n, _, v in family["samples"] if n == name + "_count"]
    assert buckets and len(sums) == 1 and len(counts) == 1, name
    bounds = [b for b, _ in buckets]
    assert bounds == sorted(bounds) and len(set(bounds)) == len(bounds) and bounds[-1] == math.inf, name
    cumulative = [c for _, c in buckets]
    assert cumulative == sorted(cumulative), "%s: buckets not cumulative: %s" % (name, cumulative)
    assert cumulative[-1] == counts[0], "%s: +Inf bucket %d != count %d" % (name, cumulative[-1], counts[0])


def value(families, name):
    assert name in families, "no metric " + name
    return families[name]["samples"][0][2]


def histogram(families, name):
    f = families[name]
    buckets = {parse_value(l["le"]): v for n, l, v in f["samples"] if n == name + "_bucket"}
    total = [v for n, _, v in f["samples"] if n == name + "_sum"][0]
    return buckets, total, buckets[math.inf]


def metric_of(stat_name, counts):
    return "rsud_" + re.sub(r"[^A-Za-z0-9_]", "_", stat_name) + ("_total" if counts else "")


def read_file(path):
    with open(path) as f:
        return f.read()


def case_metrics(h):
    h.record_background()
    prom = h.path("rsud.prom")
    h.write_config(extra="metrics: {textfile: %s, interval_s: 0.3}\n" % prom)
    h.start_rsud()
    h.epoch_ns = time.time_ns() + int(0.6e9)
    stream = h.stream(0.0, 4.0)
    fleet = h.fleet(4.3, connected=[1])

    # Mid-run: a scrape already shows the car served.
    h.wait_for(lambda: os.path.exists(prom) and value(parse_exposition(read_file(prom)),
                                                      "rsud_corrections_sent_total") > 0,
               10, "a metrics file with corrections")
    mid = parse_exposition(read_file(prom))
    mid_corrections = value(mid, "rsud_corrections_sent_total")
    finish(stream, 20, "rsu-sim stream")
    finish(fleet, 20, "rsu-fleet")
    h.stop_rsud()

    families = parse_exposition(read_file(prom))
    stats = h.stats()
    types = {"counter": 0, "gauge": 0, "histogram": 0}
    for f in families.values():
        types[f["type"]] += 1
    # Every stats-file value, under its derived name, equal at exit (both written at the drain).
    for stat, v in stats.items():
        name = metric_of(stat, True) if metric_of(stat, True) in families else metric_of(stat, False)
        assert name in families, "stats value %s is not in the metrics" % stat
        assert stat in families[name]["help"], "the help of %s does not name %s" % (name, stat)
        if stat in ("uptime_s", "process.heap_in_use_bytes", "process.heap_held_bytes"):
            continue  # the values that move between the two writes (the clock, the allocator's heap)
        got = value(families, name)
        # The stats file prints measured values to 6 digits.
        same = (math.isnan(got) and math.isnan(v)) or math.isclose(got, v, rel_tol=1e-5, abs_tol=1e-9)
        assert same, "%s: metrics %s, stats file %s" % (stat, got, v)
    sent = value(families, "rsud_corrections_sent_total")
    assert sent >= mid_corrections > 0, (sent, mid_corrections)

    # Correction latency: every sent correction, its mean against the fleet's own measure.
    buckets, total, count = histogram(families, "rsud_correction_latency_seconds")
    assert count == sent, "latency histogram %d, corrections sent %d" % (count, sent)
    received = h.corrections()
    assert received, "the fleet received no correction"
    fleet_mean = sum(c["recv_ns"] - c["sweep_ns"] for c in received) / len(received) * 1e-9
    rsud_mean = total / count
    assert fleet_mean - 0.02 <= rsud_mean <= fleet_mean + 1e-4, \
        "rsud's mean latency %.4f s, the fleet's %.4f s" % (rsud_mean, fleet_mean)
    within_100ms = buckets[0.1] / count
    within_5ms = buckets[0.005] / count

    # Its three parts, for each correction a live packet's step released (every one here but those drained
    # at the stop): they add up to the latency, each part from the same clock readings.
    parts = {p: histogram(families, "rsud_correction_%s_seconds" % p) for p in ("sweep_wait", "socket_wait", "step")}
    part_count = parts["step"][2]
    assert all(c == part_count for _, _, c in parts.values()), parts
    assert 0.9 * count <= part_count <= count, (part_count, count)
    assert parts["socket_wait"][1] >= 0 and parts["step"][1] > 0 and parts["sweep_wait"][1] > 0, parts
    if part_count == count:
        part_sum = sum(t for _, t, _ in parts.values())
        assert math.isclose(part_sum, total, rel_tol=1e-6, abs_tol=1e-6), (part_sum, total)
    # Each packet's wait in the socket (the first has no stamp: it turns them on).
    waits, wait_sum, wait_count = histogram(families, "rsud_lidar_socket_wait_seconds")

    # Sensor clock offset: one observation per data packet, all near zero (the shared clock).
    offsets, offset_sum, offset_count = histogram(families, "rsud_sensor_clock_offset_seconds")
    accepted = stats["packet.accepted"]
    assert offset_count == accepted, "offset histogram %d, data packets %d" % (offset_count, accepted)
    assert offsets[0.1] - offsets[-0.01] == offset_count, "offsets beyond [-10 ms, 100 ms]: %s" % offsets
    steps, steps_sum, steps_count = histogram(families, "rsud_lidar_step_seconds")
    assert steps_count >= accepted, (steps_count, accepted)
    assert accepted - 1 <= wait_count <= steps_count and wait_sum >= 0, (wait_count, accepted, wait_sum)
    print("ok: %d families (%d counters, %d gauges, %d histograms), every stats value equal; %d corrections, "
          "mean latency %.1f ms (the fleet measured %.1f ms), %.0f %% within 100 ms, %.0f %% within 5 ms; "
          "its parts (%d corrections): sweep wait %.2f ms, socket wait %.3f ms, step %.3f ms; %d packets, "
          "mean sensor offset %.3f ms, mean socket wait %.1f us; mean LiDAR step %.1f us over %d steps" % (
              len(families), types["counter"], types["gauge"], types["histogram"], sent, rsud_mean * 1e3,
              fleet_mean * 1e3, within_100ms * 100, within_5ms * 100, part_count,
              parts["sweep_wait"][1] / part_count * 1e3, parts["socket_wait"][1] / part_count * 1e3,
              parts["step"][1] / part_count * 1e3, offset_count, offset_sum / offset_count * 1e3,
              wait_sum / max(wait_count, 1) * 1e6, steps_sum / steps_count * 1e6, steps_count))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rsud", required=True)
    ap.add_argument("--rsu-sim", required=True)
    ap.add_argument("--fleet", required=True)
    ap.add_argument("--work", required=True)
    args = ap.parse_args()
    tools = {"rsud": args.rsud, "rsu_sim": args.rsu_sim, "fleet": args.fleet}
    return run_case(case_metrics, args.work, tools, SCENARIO)


if __name__ == "__main__":
    sys.exit(main())
