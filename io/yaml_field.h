// SPDX-License-Identifier: Apache-2.0
// Reading YAML with errors that point at the file, the line and the field:
//   scenarios/pilot.yaml:12: lidar.mount.z: expected a number, got "two"
// Unknown keys are errors too: a misspelt key silently falling back to a default is the worst kind of
// bug in an experiment description or a daemon configuration. Used by scenario files (sim/scenario.h)
// and the daemon's configuration.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <initializer_list>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/angles.h"

namespace rsu::io {

class YamlError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Parses YAML text; a syntax error becomes a YamlError "<source>:<line>: <syntax>: ...". Inline (pure,
// no file): lib/ parsers of text the caller read (the Ouster metadata) use it without linking rsu_yaml.
inline YAML::Node parse_yaml(const std::string& text, const std::string& source_name) {
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw YamlError(source_name + ":" + std::to_string(e.mark.line + 1) + ": <syntax>: " + e.msg);
  }
}
// Reads a file; one that cannot be opened becomes "<path>:0: <file>: cannot open: <the OS's reason>".
std::string read_text_file(const std::string& path);

class YamlField {
 public:
  YamlField(YAML::Node node, std::string path, const std::string& source, int line)
      : node_(std::move(node)), path_(std::move(path)), source_(source), line_(line) {}

  [[noreturn]] void fail(const std::string& what) const {
    std::ostringstream out;
    out << source_ << ':' << line_ << ": " << (path_.empty() ? "<document>" : path_) << ": " << what;
    throw YamlError(out.str());
  }

  bool is_map() const { return node_.IsMap(); }
  bool is_sequence() const { return node_.IsSequence(); }

  YamlField child(const std::string& key) const {
    const YAML::Node c = node_[key];
    const int line = c ? c.Mark().line + 1 : line_;
    return YamlField(c, path_.empty() ? key : path_ + "." + key, source_, line);
  }
  bool has(const std::string& key) const { return node_.IsMap() && node_[key]; }

  // Rejects keys outside `allowed` (typos would otherwise silently fall back to defaults).
  void expect_map(std::initializer_list<const char*> allowed) const {
    if (!node_.IsMap())
      fail("expected a mapping");
    const std::set<std::string> keys(allowed.begin(), allowed.end());
    for (const auto& kv : node_) {
      // A complex key ("? [a, b]: 1") is valid YAML but never one of ours; as<std::string>() would
      // throw yaml-cpp's own exception, escaping the file:line: field error every caller expects.
      if (!kv.first.IsScalar())
        YamlField(kv.first, path_, source_, kv.first.Mark().line + 1)
            .fail("expected a field name, got a complex key");
      const std::string key = kv.first.as<std::string>();
      if (!keys.contains(key)) {
        std::string list;
        for (const auto& k : keys)
          list += (list.empty() ? "" : ", ") + k;
        YamlField(kv.first, path_.empty() ? key : path_ + "." + key, source_, kv.first.Mark().line + 1)
            .fail("unknown field (expected one of: " + list + ")");
      }
    }
  }

  std::vector<YamlField> items() const {
    if (!node_.IsSequence())
      fail("expected a list");
    std::vector<YamlField> out;
    for (std::size_t i = 0; i < node_.size(); ++i) {
      const YAML::Node c = node_[i];
      out.emplace_back(c, path_ + "[" + std::to_string(i) + "]", source_, c.Mark().line + 1);
    }
    return out;
  }

  double number() const {
    if (!node_.IsScalar())
      fail("expected a number");
    double v = 0;
    try {
      v = node_.as<double>();
    } catch (const YAML::Exception&) {
      fail("expected a number, got \"" + node_.Scalar() + "\"");
    }
    if (!std::isfinite(v))
      fail("expected a finite number, got \"" + node_.Scalar() + "\"");
    return v;
  }
  std::string text() const {
    if (!node_.IsScalar())
      fail("expected a string");
    return node_.Scalar();
  }

  double number_or(const std::string& key, double fallback) const {
    return has(key) ? child(key).number() : fallback;
  }
  double positive_or(const std::string& key, double fallback) const {
    const double v = number_or(key, fallback);
    if (!(v > 0))
      child(key).fail("must be > 0, got " + std::to_string(v));
    return v;
  }
  double non_negative_or(const std::string& key, double fallback) const {
    const double v = number_or(key, fallback);
    if (v < 0)
      child(key).fail("must be >= 0, got " + std::to_string(v));
    return v;
  }
  double angle_deg_or(const std::string& key, double fallback_rad) const {
    return has(key) ? deg_to_rad(child(key).number()) : fallback_rad;
  }
  YamlField required(const std::string& key) const {
    if (!has(key))
      fail("missing required field \"" + key + "\"");
    return child(key);
  }
  int line() const { return line_; }

 private:
  YAML::Node node_;
  std::string path_;
  const std::string& source_;
  int line_;
};

}  // namespace rsu::io
