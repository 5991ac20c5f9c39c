// SPDX-License-Identifier: Apache-2.0
// Scenario YAML -> sim::Scenario, read through io::YamlField so that every error names the file, the
// line and the field.
#include "sim/scenario.h"

#include <cmath>
#include <set>

#include "common/angles.h"
#include "io/yaml_field.h"

namespace rsu::sim {
namespace {

using io::YamlField;

Pose3 read_mount(const YamlField& f) {
  f.expect_map({"x", "y", "z", "roll_deg", "pitch_deg", "yaw_deg"});
  Pose3 p;
  p.x = f.number_or("x", 0);
  p.y = f.number_or("y", 0);
  p.z = f.number_or("z", 0);
  p.roll = f.angle_deg_or("roll_deg", 0);
  p.pitch = f.angle_deg_or("pitch_deg", 0);
  p.yaw = f.angle_deg_or("yaw_deg", 0);
  return p;
}

LidarConfig read_lidar(const YamlField& f) {
  f.expect_map({"model", "rpm", "mount", "noise", "start_azimuth_deg", "mount_motion"});
  LidarConfig lidar;
  const YamlField model = f.required("model");
  lidar.model_name = model.text();
  auto resolved = lidar::sensor_model_by_name(lidar.model_name);
  if (!resolved)
    model.fail("unknown LiDAR model \"" + lidar.model_name + "\" (vlp16, vlp32c, genericN)");
  lidar.model = *resolved;
  if (f.has("rpm")) {
    const double rpm = f.child("rpm").number();
    if (rpm < 300 || rpm > 1200)
      f.child("rpm").fail("must be within [300, 1200] rpm");
    lidar.model.rpm = rpm;
  }
  if (f.has("mount"))
    lidar.mount = read_mount(f.child("mount"));
  if (f.has("noise")) {
    const YamlField n = f.child("noise");
    n.expect_map({"range_sigma_m", "angle_sigma_rad", "seed"});
    lidar.noise.range_sigma_m = n.non_negative_or("range_sigma_m", lidar.noise.range_sigma_m);
    lidar.noise.angle_sigma_rad = n.non_negative_or("angle_sigma_rad", lidar.noise.angle_sigma_rad);
    if (n.has("seed")) {
      const double seed = n.child("seed").number();
      if (seed < 0 || seed != std::floor(seed))
        n.child("seed").fail("must be a non-negative integer");
      lidar.noise.seed = static_cast<std::uint64_t>(seed);
    }
  }
  lidar.start_azimuth_deg = f.number_or("start_azimuth_deg", 0.0);
  return lidar;
}

// Objects may carry `repeat: {count, dx, dy}` to place a row of copies (lamps every 10 m, say).
template <typename T, typename ReadOne>
void read_objects(const YamlField& list, std::vector<T>& out, ReadOne read_one) {
  for (const YamlField& item : list.items()) {
    const T base = read_one(item);
    int count = 1;
    double dx = 0, dy = 0;
    if (item.has("repeat")) {
      const YamlField r = item.child("repeat");
      r.expect_map({"count", "dx", "dy"});
      const double c = r.required("count").number();
      if (c < 1 || c > 10000 || c != std::floor(c))
        r.child("count").fail("must be an integer in [1, 10000]");
      count = static_cast<int>(c);
      dx = r.number_or("dx", 0);
      dy = r.number_or("dy", 0);
    }
    for (int i = 0; i < count; ++i) {
      T copy = base;
      copy.x += dx * i;
      copy.y += dy * i;
      out.push_back(copy);
    }
  }
}

// Buildings and shrubs: an object at (x, y) turned by yaw, with length, width and height.
template <typename T>
T read_placed_box(const YamlField& f) {
  f.expect_map({"x", "y", "yaw_deg", "length", "width", "height", "repeat"});
  T o;
  o.x = f.number_or("x", 0);
  o.y = f.number_or("y", 0);
  o.yaw = f.angle_deg_or("yaw_deg", 0);
  o.length = f.positive_or("length", o.length);
  o.width = f.positive_or("width", o.width);
  o.height = f.positive_or("height", o.height);
  return o;
}

VehicleShape read_shape(const YamlField& f) {
  f.expect_map({"length", "width", "height", "corner_radius", "ground_clearance", "belt_height",
                "cabin_inset", "hood_length", "windscreen_run", "rear_slope_run", "wheel_radius",
                "wheel_width", "wheelbase"});
  VehicleShape s;
  s.length = f.positive_or("length", s.length);
  s.width = f.positive_or("width", s.width);
  s.height = f.positive_or("height", s.height);
  if (s.length > 25 || s.width > 5 || s.height > 6)
    f.fail("vehicle larger than 25 x 5 x 6 m");
  s.corner_radius = f.non_negative_or("corner_radius", s.corner_radius);
  s.ground_clearance = f.non_negative_or("ground_clearance", s.ground_clearance);
  s.belt_height = f.positive_or("belt_height", s.belt_height);
  s.cabin_inset = f.non_negative_or("cabin_inset", s.cabin_inset);
  s.hood_length = f.non_negative_or("hood_length", s.hood_length);
  s.windscreen_run = f.non_negative_or("windscreen_run", s.windscreen_run);
  s.rear_slope_run = f.non_negative_or("rear_slope_run", s.rear_slope_run);
  s.wheel_radius = f.positive_or("wheel_radius", s.wheel_radius);
  s.wheel_width = f.positive_or("wheel_width", s.wheel_width);
  s.wheelbase = f.positive_or("wheelbase", s.wheelbase);
  if (2 * s.corner_radius > s.width)
    f.child("corner_radius").fail("must be at most half the width");
  if (s.belt_height >= s.height || s.ground_clearance >= s.belt_height)
    f.fail("need ground_clearance < belt_height < height");
  if (s.wheelbase + 2 * s.wheel_radius > s.length)
    f.child("wheelbase").fail("wheels do not fit the length");
  return s;
}

Pose2 read_pose2(const YamlField& f) {
  return Pose2{f.number_or("x", 0), f.number_or("y", 0), f.angle_deg_or("yaw_deg", 0)};
}

Trajectory read_trajectory(const YamlField& f) {
  f.expect_map({"static", "spin", "waypoints", "interpolation"});
  const int kinds = f.has("static") + f.has("spin") + f.has("waypoints");
  if (kinds != 1)
    f.fail("exactly one of static, spin, waypoints is required");
  if (f.has("interpolation") && !f.has("waypoints"))
    f.child("interpolation").fail("only waypoints are interpolated");
  if (f.has("static")) {
    const YamlField s = f.child("static");
    s.expect_map({"x", "y", "yaw_deg"});
    return StaticPose{read_pose2(s)};
  }
  if (f.has("spin")) {
    const YamlField s = f.child("spin");
    s.expect_map({"x", "y", "yaw0_deg", "rate_deg_s", "t0_s"});
    Spin spin;
    spin.x = s.number_or("x", 0);
    spin.y = s.number_or("y", 0);
    spin.yaw0 = s.angle_deg_or("yaw0_deg", 0);
    spin.rate_rad_s = s.angle_deg_or("rate_deg_s", 0);
    spin.t0 = from_seconds(s.number_or("t0_s", 0));
    return spin;
  }
  Waypoints w;
  if (f.has("interpolation")) {
    const std::string mode = f.child("interpolation").text();
    if (mode != "linear" && mode != "smooth")
      f.child("interpolation").fail("must be linear or smooth");
    w.smooth = mode == "smooth";
  }
  for (const YamlField& item : f.child("waypoints").items()) {
    item.expect_map({"t_s", "x", "y", "yaw_deg"});
    const TimeNs t = from_seconds(item.required("t_s").number());
    if (!w.points.empty() && t <= w.points.back().t)
      item.child("t_s").fail("times must increase");
    w.points.push_back({t, read_pose2(item)});
  }
  if (w.points.empty())
    f.child("waypoints").fail("needs at least one waypoint");
  return w;
}

Scene read_scene(const YamlField& f) {
  f.expect_map({"ground", "reflectivity", "buildings", "poles", "trees", "shrubs"});
  Scene scene;
  if (f.has("ground")) {
    const YamlField g = f.child("ground");
    g.expect_map({"half_extent_m"});
    scene.ground.half_extent_m = g.positive_or("half_extent_m", scene.ground.half_extent_m);
  }
  if (f.has("reflectivity")) {
    const YamlField r = f.child("reflectivity");
    r.expect_map({"ground", "building", "pole", "vegetation", "vehicle"});
    auto read = [&](const char* key, double& v) {
      v = r.number_or(key, v);
      if (v < 0 || v > 1)
        r.child(key).fail("must be within [0, 1]");
    };
    read("ground", scene.reflectivity.ground);
    read("building", scene.reflectivity.building);
    read("pole", scene.reflectivity.pole);
    read("vegetation", scene.reflectivity.vegetation);
    read("vehicle", scene.reflectivity.vehicle);
  }
  if (f.has("buildings"))
    read_objects(f.child("buildings"), scene.buildings, read_placed_box<Building>);
  if (f.has("poles")) {
    read_objects(f.child("poles"), scene.poles, [](const YamlField& p) {
      p.expect_map({"x", "y", "radius", "height", "arm_length", "arm_yaw_deg", "repeat"});
      Pole o;
      o.x = p.number_or("x", 0);
      o.y = p.number_or("y", 0);
      o.radius = p.positive_or("radius", o.radius);
      o.height = p.positive_or("height", o.height);
      o.arm_length = p.non_negative_or("arm_length", o.arm_length);
      o.arm_yaw = p.angle_deg_or("arm_yaw_deg", 0);
      return o;
    });
  }
  if (f.has("trees")) {
    read_objects(f.child("trees"), scene.trees, [](const YamlField& t) {
      t.expect_map({"x", "y", "trunk_radius", "trunk_height", "crown_radius", "repeat"});
      Tree o;
      o.x = t.number_or("x", 0);
      o.y = t.number_or("y", 0);
      o.trunk_radius = t.positive_or("trunk_radius", o.trunk_radius);
      o.trunk_height = t.positive_or("trunk_height", o.trunk_height);
      o.crown_radius = t.positive_or("crown_radius", o.crown_radius);
      return o;
    });
  }
  if (f.has("shrubs"))
    read_objects(f.child("shrubs"), scene.shrubs, read_placed_box<Shrub>);
  return scene;
}

}  // namespace

namespace {

Scenario read_scenario(const YAML::Node& root, const std::string& source_name) {
  const YamlField doc(root, "", source_name, 1);
  doc.expect_map({"name", "lidar", "scene", "vehicles", "simulation"});

  Scenario s;
  s.source = source_name;
  s.name = doc.has("name") ? doc.child("name").text() : source_name;
  s.lidar = read_lidar(doc.required("lidar"));
  if (doc.child("lidar").has("mount_motion")) {
    const YamlField motion = doc.child("lidar").child("mount_motion");
    s.lidar.mount_motion = read_trajectory(motion);
    if (std::holds_alternative<Spin>(*s.lidar.mount_motion))
      motion.fail("a mount does not spin: static or waypoints");
  }
  if (doc.has("scene"))
    s.scene = read_scene(doc.child("scene"));
  if (doc.has("vehicles")) {
    std::set<std::uint32_t> ids;
    for (const YamlField& v : doc.child("vehicles").items()) {
      v.expect_map({"id", "shape", "trajectory"});
      Vehicle vehicle;
      const double id = v.required("id").number();
      if (id < 0 || id > 4294967295.0 || id != std::floor(id))
        v.child("id").fail("must be a 32-bit unsigned integer");
      vehicle.id = static_cast<std::uint32_t>(id);
      if (!ids.insert(vehicle.id).second)
        v.child("id").fail("duplicate vehicle id");
      if (v.has("shape"))
        vehicle.shape = read_shape(v.child("shape"));
      vehicle.trajectory = read_trajectory(v.required("trajectory"));
      s.scene.vehicles.push_back(vehicle);
    }
  }
  if (doc.has("simulation")) {
    const YamlField sim = doc.child("simulation");
    sim.expect_map({"start_s", "frames"});
    s.start_ns = from_seconds(sim.number_or("start_s", 0));
    const double frames = sim.number_or("frames", s.frames);
    if (frames < 1 || frames > 100000 || frames != std::floor(frames))
      sim.child("frames").fail("must be an integer in [1, 100000]");
    s.frames = static_cast<int>(frames);
  }
  return s;
}

}  // namespace

MovingMount moving_mount(const LidarConfig& lidar) {
  MovingMount out;
  const Pose3& m = lidar.mount;
  // The carrier stands at the sensor's x, y (so that its yaw turns the sensor about its own vertical);
  // the sensor sits on it at its height, tilt and heading.
  out.mount_on_carrier = Pose3{0.0, 0.0, m.z, m.roll, m.pitch, m.yaw};
  Waypoints w;
  if (const auto* given = lidar.mount_motion ? std::get_if<Waypoints>(&*lidar.mount_motion) : nullptr) {
    w = *given;
  } else if (const auto* still =
                 lidar.mount_motion ? std::get_if<StaticPose>(&*lidar.mount_motion) : nullptr) {
    w.points.push_back({0, still->pose});
  } else {
    w.points.push_back({0, Pose2{}});
  }
  for (TimedPose& p : w.points) {
    p.pose.x += m.x;
    p.pose.y += m.y;
  }
  out.carrier = w;
  return out;
}

Scenario parse_scenario(std::string_view yaml_text, const std::string& source_name) {
  try {
    return read_scenario(io::parse_yaml(std::string(yaml_text), source_name), source_name);
  } catch (const io::YamlError& e) {
    throw ScenarioError(e.what());
  }
}

Scenario load_scenario_file(const std::string& path) {
  try {
    return parse_scenario(io::read_text_file(path), path);
  } catch (const io::YamlError& e) {
    throw ScenarioError(e.what());
  }
}

NamedVehicleShape parse_vehicle_shape(std::string_view yaml_text, const std::string& source_name) {
  try {
    const YamlField root(io::parse_yaml(std::string(yaml_text), source_name), "", source_name, 1);
    root.expect_map({"name", "shape"});
    NamedVehicleShape out;
    if (root.has("name"))
      out.name = root.child("name").text();
    out.shape = read_shape(root.required("shape"));
    return out;
  } catch (const io::YamlError& e) {
    throw ScenarioError(e.what());
  }
}

NamedVehicleShape load_vehicle_shape_file(const std::string& path) {
  try {
    return parse_vehicle_shape(io::read_text_file(path), path);
  } catch (const io::YamlError& e) {
    throw ScenarioError(e.what());
  }
}

}  // namespace rsu::sim
