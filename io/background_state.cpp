// SPDX-License-Identifier: Apache-2.0
#include "io/background_state.h"

#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/pcd_io.h"
#include "io/text_file.h"
#include "io/yaml_field.h"

namespace rsu::io {
namespace {

constexpr const char* kFormat = "rsud-background";
constexpr const char* kManifest = "background.yaml";
constexpr const char* kPoints = "background.pcd";

std::string in(const std::string& directory, const char* name) {
  return (std::filesystem::path(directory) / name).string();
}

// Flushes `path` to the disk, so that the rename after it never publishes an empty file.
void sync_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    throw BackgroundStateError(path + ": cannot open to flush: " + errno_text());
  const bool ok = ::fsync(fd) == 0;
  const std::string reason = ok ? "" : errno_text();
  ::close(fd);
  if (!ok)
    throw BackgroundStateError(path + ": cannot flush to disk: " + reason);
}

void publish(const std::string& tmp, const std::string& path) {
  sync_file(tmp);
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec)
    throw BackgroundStateError(path + ": cannot replace: " + ec.message());
}

std::string hex64(std::uint64_t v) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(v));
  return text;
}

}  // namespace

std::uint64_t fnv1a64(const std::string& bytes) {
  std::uint64_t h = 14695981039346656037ULL;
  for (const char c : bytes) {
    h ^= static_cast<std::uint8_t>(c);
    h *= 1099511628211ULL;
  }
  return h;
}

void save_background_state(const std::string& directory, const PersistedBackground& background) {
  const std::string points_path = in(directory, kPoints);
  std::vector<lidar::LidarPoint> all;
  for (const auto& frame : background.frames)
    all.insert(all.end(), frame.begin(), frame.end());
  try {
    write_pcd(points_path + ".tmp", all);
  } catch (const std::exception& e) {
    throw BackgroundStateError(e.what());
  }
  std::string points_bytes;
  try {
    points_bytes = read_whole_file(points_path + ".tmp");
  } catch (const FileError& e) {
    throw BackgroundStateError(e.what());
  }
  publish(points_path + ".tmp", points_path);

  std::ostringstream m;
  m.precision(17);
  const Pose3& p = background.mount;
  m << "# rsud's learned background (sensor frame) and what it belongs to; written by rsud, do not edit.\n"
    << "format: " << kFormat << "\nversion: " << kBackgroundStateVersion << "\n"
    << "sensor_model: \"" << background.sensor_model << "\"\n"
    << "mount_rad: {x: " << p.x << ", y: " << p.y << ", z: " << p.z << ", roll: " << p.roll
    << ", pitch: " << p.pitch << ", yaw: " << p.yaw << "}\n"
    << "frame_points: [";
  for (std::size_t i = 0; i < background.frames.size(); ++i)
    m << (i ? ", " : "") << background.frames[i].size();
  m << "]\npoints_file: " << kPoints << "\npoints_fnv1a64: \"" << hex64(fnv1a64(points_bytes)) << "\"\n";
  const std::string manifest_path = in(directory, kManifest);
  {
    std::ofstream out(manifest_path + ".tmp", std::ios::trunc);
    if (!out)
      throw BackgroundStateError(manifest_path + ".tmp: cannot open: " + errno_text());
    out << m.str();
    out.flush();
    if (!out)
      throw BackgroundStateError(manifest_path + ".tmp: cannot write: " + errno_text());
  }
  publish(manifest_path + ".tmp", manifest_path);
}

std::optional<PersistedBackground> load_background_state(const std::string& directory) {
  const std::string manifest_path = in(directory, kManifest);
  std::error_code ec;
  if (!std::filesystem::exists(manifest_path, ec))
    return std::nullopt;
  PersistedBackground out;
  std::vector<std::size_t> frame_points;
  std::string expected_hash;
  try {
    const std::string text = read_whole_file(manifest_path);
    const YamlField f(parse_yaml(text, manifest_path), "", manifest_path, 1);
    f.expect_map(
        {"format", "version", "sensor_model", "mount_rad", "frame_points", "points_file", "points_fnv1a64"});
    if (f.required("format").text() != kFormat)
      f.child("format").fail("not an rsud background (format \"" + f.child("format").text() + "\")");
    const double version = f.required("version").number();
    if (version != kBackgroundStateVersion)
      f.child("version").fail("version " + f.child("version").text() + " (this rsud reads version " +
                              std::to_string(kBackgroundStateVersion) + ")");
    out.sensor_model = f.required("sensor_model").text();
    const YamlField m = f.required("mount_rad");
    m.expect_map({"x", "y", "z", "roll", "pitch", "yaw"});
    out.mount = Pose3{m.required("x").number(),    m.required("y").number(),     m.required("z").number(),
                      m.required("roll").number(), m.required("pitch").number(), m.required("yaw").number()};
    for (const YamlField& n : f.required("frame_points").items()) {
      const double v = n.number();
      if (v < 0 || v > 1e8 || v != std::floor(v))
        n.fail("expected a point count");
      frame_points.push_back(static_cast<std::size_t>(v));
    }
    if (frame_points.empty())
      f.child("frame_points").fail("no rotation");
    if (f.required("points_file").text() != kPoints)
      f.child("points_file").fail(std::string("expected ") + kPoints);
    expected_hash = f.required("points_fnv1a64").text();
  } catch (const YamlError& e) {
    throw BackgroundStateError(e.what());
  } catch (const FileError& e) {
    throw BackgroundStateError(e.what());
  }
  const std::string points_path = in(directory, kPoints);
  std::string bytes;
  try {
    bytes = read_whole_file(points_path);
  } catch (const FileError& e) {
    throw BackgroundStateError(e.what());
  }
  if (hex64(fnv1a64(bytes)) != expected_hash)
    throw BackgroundStateError(points_path + ": not the file " + manifest_path +
                               " describes (its hash differs: cut off, or from another run)");
  std::vector<lidar::LidarPoint> all;
  try {
    all = read_pcd(points_path);
  } catch (const PcdError& e) {
    throw BackgroundStateError(e.what());
  }
  std::size_t total = 0;
  for (const std::size_t n : frame_points)
    total += n;
  if (total != all.size())
    throw BackgroundStateError(points_path + ": " + std::to_string(all.size()) + " points, " + manifest_path +
                               " counts " + std::to_string(total));
  std::size_t at = 0;
  for (const std::size_t n : frame_points) {
    out.frames.emplace_back(all.begin() + static_cast<std::ptrdiff_t>(at),
                            all.begin() + static_cast<std::ptrdiff_t>(at + n));
    at += n;
  }
  return out;
}

}  // namespace rsu::io
