// SPDX-License-Identifier: Apache-2.0
#include "sim/raycaster.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "common/angles.h"
#include "sim/parallel_indices.h"
#include "sim/trajectory.h"
#include "sim/vehicle_mesh.h"

namespace rsu::sim {
namespace {

constexpr std::size_t kClassCount = 6;
constexpr unsigned kPacketWidth = 16;
// cast_batch's chunk of rays: small enough for the stack, so no allocation per ray or per chunk.
constexpr std::size_t kChunk = 64;

std::size_t class_index(SurfaceClass c) {
  return static_cast<std::size_t>(c);
}

struct DeviceRelease {
  void operator()(RTCDevice device) const { rtcReleaseDevice(device); }
};
struct SceneRelease {
  void operator()(RTCScene scene) const { rtcReleaseScene(scene); }
};
using DeviceHandle = std::unique_ptr<RTCDeviceTy, DeviceRelease>;
using SceneHandle = std::unique_ptr<RTCSceneTy, SceneRelease>;

const char* error_name(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE:
      return "RTC_ERROR_NONE";
    case RTC_ERROR_UNKNOWN:
      return "RTC_ERROR_UNKNOWN";
    case RTC_ERROR_INVALID_ARGUMENT:
      return "RTC_ERROR_INVALID_ARGUMENT";
    case RTC_ERROR_INVALID_OPERATION:
      return "RTC_ERROR_INVALID_OPERATION";
    case RTC_ERROR_OUT_OF_MEMORY:
      return "RTC_ERROR_OUT_OF_MEMORY";
    case RTC_ERROR_UNSUPPORTED_CPU:
      return "RTC_ERROR_UNSUPPORTED_CPU";
    case RTC_ERROR_CANCELLED:
      return "RTC_ERROR_CANCELLED";
  }
  return "unknown Embree error";
}

bool positive(double v) {
  return std::isfinite(v) && v > 0.0;
}
bool finite(double v) {
  return std::isfinite(v);
}

void require(bool ok, const std::string& what) {
  if (!ok) {
    throw std::invalid_argument(what);
  }
}

Eigen::Affine3d planar_pose(double x, double y, double yaw, double z = 0.0) {
  return Eigen::Translation3d(x, y, z) * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ());
}

// A pole with an optional lamp: a horizontal arm at the top along arm_yaw and a lamp head under its
// end (the head is what a LiDAR mostly sees of a street lamp above the road).
TriangleMesh make_pole_mesh(const Pole& pole, int segments) {
  TriangleMesh mesh =
      transformed(make_cylinder(pole.radius, 0.0, pole.height, segments), planar_pose(pole.x, pole.y, 0.0));
  if (pole.arm_length > 0.0) {
    const double arm_radius = std::max(0.5 * pole.radius, 0.03);
    // Cylinder along z from 0 to arm_length, laid along +x by +90 deg about y, then turned to arm_yaw.
    const Eigen::Affine3d arm_pose = planar_pose(pole.x, pole.y, pole.arm_yaw, pole.height - arm_radius) *
                                     Eigen::AngleAxisd(0.5 * kPi, Eigen::Vector3d::UnitY());
    mesh.append(transformed(make_cylinder(arm_radius, 0.0, pole.arm_length, segments), arm_pose));
    const double head_length = std::min(0.5, pole.arm_length);
    const double head_top = pole.height - 1.5 * arm_radius;
    const TriangleMesh head =
        make_box({pole.arm_length - head_length, -0.15, head_top - 0.15}, {pole.arm_length, 0.15, head_top});
    mesh.append(transformed(head, planar_pose(pole.x, pole.y, pole.arm_yaw)));
  }
  return mesh;
}

void validate_static_scene(const Scene& scene) {
  require(positive(scene.ground.half_extent_m), "ground: half_extent_m must be positive and finite");
  for (std::size_t i = 0; i < scene.buildings.size(); ++i) {
    const Building& b = scene.buildings[i];
    require(finite(b.x) && finite(b.y) && finite(b.yaw) && positive(b.length) && positive(b.width) &&
                positive(b.height),
            "building " + std::to_string(i) + ": position and yaw must be finite, sizes positive");
  }
  for (std::size_t i = 0; i < scene.poles.size(); ++i) {
    const Pole& p = scene.poles[i];
    require(finite(p.x) && finite(p.y) && positive(p.radius) && positive(p.height) && finite(p.arm_length) &&
                p.arm_length >= 0.0 && finite(p.arm_yaw),
            "pole " + std::to_string(i) + ": position must be finite, radius and height positive, arm >= 0");
  }
  for (std::size_t i = 0; i < scene.trees.size(); ++i) {
    const Tree& t = scene.trees[i];
    require(finite(t.x) && finite(t.y) && positive(t.trunk_radius) && positive(t.trunk_height) &&
                positive(t.crown_radius),
            "tree " + std::to_string(i) + ": position must be finite, sizes positive");
  }
  for (std::size_t i = 0; i < scene.shrubs.size(); ++i) {
    const Shrub& s = scene.shrubs[i];
    require(finite(s.x) && finite(s.y) && finite(s.yaw) && positive(s.length) && positive(s.width) &&
                positive(s.height),
            "shrub " + std::to_string(i) + ": position and yaw must be finite, sizes positive");
  }
  const Reflectivity& r = scene.reflectivity;
  for (const double v : {r.ground, r.building, r.pole, r.vegetation, r.vehicle}) {
    require(finite(v) && v >= 0.0 && v <= 1.0, "reflectivity: every value must be in [0, 1]");
  }
}

// Unit normal facing back towards the ray (the side the LiDAR sees), whatever Embree's winding rule.
Eigen::Vector3d facing_normal(const Eigen::Vector3d& ng, const Eigen::Vector3d& direction) {
  const double n = ng.norm();
  if (!(n > 0.0)) {
    return -direction;
  }
  const Eigen::Vector3d unit = ng / n;
  return unit.dot(direction) > 0.0 ? Eigen::Vector3d(-unit) : unit;
}

void set_ray(RTCRayHit& rh, const Eigen::Vector3d& o, const Eigen::Vector3d& d, float tfar) {
  rh.ray.org_x = static_cast<float>(o.x());
  rh.ray.org_y = static_cast<float>(o.y());
  rh.ray.org_z = static_cast<float>(o.z());
  rh.ray.tnear = 0.0F;
  rh.ray.dir_x = static_cast<float>(d.x());
  rh.ray.dir_y = static_cast<float>(d.y());
  rh.ray.dir_z = static_cast<float>(d.z());
  rh.ray.time = 0.0F;
  rh.ray.tfar = tfar;
  rh.ray.mask = 0xFFFFFFFFU;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

float to_tfar(double max_range) {
  return std::isfinite(max_range) ? static_cast<float>(max_range) : std::numeric_limits<float>::infinity();
}

// A ray after input checks: unit direction, a usable range limit.
struct CheckedRay {
  bool valid = false;
  Eigen::Vector3d origin;
  Eigen::Vector3d direction;
  double max_range = 0.0;
};

// Written in place (the batch path checks every ray: no temporary to copy).
inline void check_ray(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double max_range,
                      CheckedRay& r) {
  const double n = direction.norm();
  r.valid =
      origin.allFinite() && direction.allFinite() && n > 0.0 && !std::isnan(max_range) && max_range > 0.0;
  if (!r.valid) {
    return;
  }
  r.origin = origin;
  r.direction = direction / n;
  r.max_range = max_range;
}

// Does the ray segment (0, limit] pass within `radius` of `centre`?
bool ray_meets_sphere(const CheckedRay& ray, const Eigen::Vector3d& centre, double radius, double limit) {
  const Eigen::Vector3d w = centre - ray.origin;
  const double along = w.dot(ray.direction);
  if (along + radius < 0.0 || along - radius > limit) {
    return false;
  }
  return w.squaredNorm() - along * along <= radius * radius;
}

// The ground is the plane z = 0 within +-half_extent in x and y (make_ground_square's two triangles),
// intersected here rather than in the BVH, where its two triangles spanned the whole scene: bench_sim's
// batched casting 3-17 % and single rays 15-20 % faster, same run. Range along the unit direction (as
// Embree's tfar, in float), infinity when the ray misses it; from either side, as Embree's triangles.
float ground_range(const CheckedRay& ray, double half_extent) {
  const double t = -ray.origin.z() / ray.direction.z();
  if (!(t > 0.0) || !std::isfinite(t)) {  // along it, from it or away from it
    return std::numeric_limits<float>::infinity();
  }
  const double x = ray.origin.x() + t * ray.direction.x();
  const double y = ray.origin.y() + t * ray.direction.y();
  if (std::abs(x) > half_extent || std::abs(y) > half_extent) {
    return std::numeric_limits<float>::infinity();
  }
  return static_cast<float>(t);
}

}  // namespace

const char* to_string(SurfaceClass surface) {
  switch (surface) {
    case SurfaceClass::kNone:
      return "none";
    case SurfaceClass::kGround:
      return "ground";
    case SurfaceClass::kBuilding:
      return "building";
    case SurfaceClass::kPole:
      return "pole";
    case SurfaceClass::kVegetation:
      return "vegetation";
    case SurfaceClass::kVehicle:
      return "vehicle";
  }
  return "unknown";
}

struct Raycaster::Impl {
  struct VehicleEntry {
    std::uint32_t id = 0;
    Trajectory trajectory;
    TriangleMesh mesh;
    SceneHandle bvh;
    Eigen::Vector3d bound_centre = Eigen::Vector3d::Zero();  // vehicle frame
    double bound_radius = 0.0;
  };

  // Declared first so that it is destroyed last (scenes must be released before their device).
  std::string last_error_message;
  DeviceHandle device;
  SceneHandle static_scene;
  std::array<TriangleMesh, kClassCount> static_meshes;
  std::vector<SurfaceClass> class_of_geometry;  // indexed by Embree geomID
  std::array<double, kClassCount> reflectivity{};
  std::vector<VehicleEntry> vehicles;
  RaycasterConfig config;
  bool packet16_native = false;
  double ground_half_extent = 0.0;  // as the ground's float vertices hold it

  static void on_error(void* user, RTCError /*code*/, const char* message) {
    static_cast<Impl*>(user)->last_error_message = message != nullptr ? message : "";
  }

  void check(const char* step) const {
    const RTCError code = rtcGetDeviceError(device.get());
    if (code != RTC_ERROR_NONE) {
      throw std::runtime_error(std::string("Embree error during ") + step + ": " + error_name(code) + ": " +
                               last_error_message);
    }
  }

  SceneHandle new_scene() {
    SceneHandle scene(rtcNewScene(device.get()));
    check("rtcNewScene");
    // Robust traversal: rays that graze a shared edge (the ground's diagonal, a box's corner) must
    // not slip through between two triangles.
    rtcSetSceneFlags(scene.get(), config.robust_traversal ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(scene.get(), RTC_BUILD_QUALITY_HIGH);
    check("scene setup");
    return scene;
  }

  void attach(RTCScene scene, const TriangleMesh& mesh, unsigned geometry_id) {
    const auto vertex_count = static_cast<int>(mesh.vertices.size());
    for (const auto& t : mesh.triangles) {
      require((t.array() >= 0).all() && (t.array() < vertex_count).all(),
              "mesh: triangle index out of range");
    }
    for (const auto& v : mesh.vertices) {
      require(v.allFinite(), "mesh: non-finite vertex");
    }
    RTCGeometry geometry = rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
    check("rtcNewGeometry");
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.vertices.size()));
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.triangles.size()));
    if (vertices == nullptr || indices == nullptr) {
      rtcReleaseGeometry(geometry);
      check("rtcSetNewGeometryBuffer");
      throw std::runtime_error("Embree error during rtcSetNewGeometryBuffer: no buffer returned");
    }
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        vertices[3 * i + static_cast<std::size_t>(k)] = mesh.vertices[i][k];
      }
    }
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        indices[3 * i + static_cast<std::size_t>(k)] = static_cast<unsigned>(mesh.triangles[i][k]);
      }
    }
    rtcCommitGeometry(geometry);
    rtcAttachGeometryByID(scene, geometry, geometry_id);
    rtcReleaseGeometry(geometry);  // the scene holds its own reference
    check("geometry commit");
  }

  void build_static(const Scene& scene) {
    validate_static_scene(scene);
    auto& ground = static_meshes[class_index(SurfaceClass::kGround)];
    auto& buildings = static_meshes[class_index(SurfaceClass::kBuilding)];
    auto& poles = static_meshes[class_index(SurfaceClass::kPole)];
    auto& vegetation = static_meshes[class_index(SurfaceClass::kVegetation)];
    ground = make_ground_square(scene.ground.half_extent_m);
    for (const Building& b : scene.buildings) {
      buildings.append(transformed(
          make_box({-0.5 * b.length, -0.5 * b.width, 0.0}, {0.5 * b.length, 0.5 * b.width, b.height}),
          planar_pose(b.x, b.y, b.yaw)));
    }
    for (const Pole& p : scene.poles) {
      poles.append(make_pole_mesh(p, config.cylinder_segments));
    }
    for (const Tree& t : scene.trees) {
      vegetation.append(
          transformed(make_cylinder(t.trunk_radius, 0.0, t.trunk_height, config.cylinder_segments),
                      planar_pose(t.x, t.y, 0.0)));
      vegetation.append(transformed(make_sphere(t.crown_radius, config.sphere_subdivisions),
                                    planar_pose(t.x, t.y, 0.0, t.trunk_height + 0.7 * t.crown_radius)));
    }
    for (const Shrub& s : scene.shrubs) {
      const Eigen::Vector3d radii(0.5 * s.length, 0.5 * s.width, 0.5 * s.height);
      vegetation.append(transformed(make_ellipsoid(radii, config.sphere_subdivisions),
                                    planar_pose(s.x, s.y, s.yaw, 0.5 * s.height)));
    }
    ground_half_extent = static_cast<double>(static_cast<float>(scene.ground.half_extent_m));
    static_scene = new_scene();
    for (const SurfaceClass c : {SurfaceClass::kBuilding, SurfaceClass::kPole, SurfaceClass::kVegetation}) {
      const TriangleMesh& mesh = static_meshes[class_index(c)];
      if (!mesh.empty()) {
        attach(static_scene.get(), mesh, static_cast<unsigned>(class_of_geometry.size()));
        class_of_geometry.push_back(c);
      }
    }
    rtcCommitScene(static_scene.get());
    check("static scene build");
  }

  void build_vehicles(const Scene& scene) {
    std::set<std::uint32_t> ids;
    for (const Vehicle& v : scene.vehicles) {
      const std::string name = "vehicle " + std::to_string(v.id) + ": ";
      require(ids.insert(v.id).second, name + "id appears more than once");
      VehicleEntry entry;
      entry.id = v.id;
      entry.trajectory = v.trajectory;
      try {
        validate_trajectory(v.trajectory);
        entry.mesh = make_vehicle_mesh(v.shape);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(name + e.what());
      }
      Eigen::Vector3f lo = entry.mesh.vertices.front();
      Eigen::Vector3f hi = lo;
      for (const auto& p : entry.mesh.vertices) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
      entry.bound_centre = (0.5F * (lo + hi)).cast<double>();
      for (const auto& p : entry.mesh.vertices) {
        entry.bound_radius = std::max(entry.bound_radius, (p.cast<double>() - entry.bound_centre).norm());
      }
      entry.bound_radius += 1e-3;  // float vertices
      entry.bvh = new_scene();
      attach(entry.bvh.get(), entry.mesh, 0);
      rtcCommitScene(entry.bvh.get());
      check("vehicle scene build");
      vehicles.push_back(std::move(entry));
    }
  }

  void finish_static_hit(const RTCHit& h, float tfar, const Eigen::Vector3d& direction, RayHit& out) const {
    const SurfaceClass c = class_of_geometry[h.geomID];
    out.range = static_cast<double>(tfar);
    out.normal = facing_normal(Eigen::Vector3f(h.Ng_x, h.Ng_y, h.Ng_z).cast<double>(), direction);
    out.surface = c;
    out.reflectivity = reflectivity[class_index(c)];
    out.vehicle_id = 0;
  }

  // The ground's range if nearer than the ray's limit, else infinity: the BVH is searched up to it.
  float ground_within(const CheckedRay& ray) const {
    const float ground = ground_range(ray, ground_half_extent);
    return ground <= to_tfar(ray.max_range) ? ground : std::numeric_limits<float>::infinity();
  }

  // What the BVH missed before the ground (or at its range: a building's foot) is the ground.
  void finish_ground_hit(float ground, const Eigen::Vector3d& direction, RayHit& out) const {
    out.range = static_cast<double>(ground);
    out.normal = facing_normal(Eigen::Vector3d::UnitZ(), direction);
    out.surface = SurfaceClass::kGround;
    out.reflectivity = reflectivity[class_index(SurfaceClass::kGround)];
    out.vehicle_id = 0;
  }

  void intersect_static(const CheckedRay& ray, RayHit& out) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    const float ground = ground_within(ray);
    set_ray(rh, ray.origin, ray.direction, std::min(to_tfar(ray.max_range), ground));
    rtcIntersect1(static_scene.get(), &context, &rh);
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
      finish_static_hit(rh.hit, rh.ray.tfar, ray.direction, out);
    } else if (std::isfinite(ground)) {
      finish_ground_hit(ground, ray.direction, out);
    }
  }

  // A vehicle's pose at one time, and its rotation once a ray needs it: computed once for all the rays
  // fired at that time that come in a row (an Ouster column's beams), by the same expressions as
  // before, so the same bits.
  struct PosedVehicle {
    TimeNs time_ns = 0;
    bool valid = false;
    bool rotated = false;
    Pose2 pose;
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  };

  static void pose_vehicle(const VehicleEntry& v, TimeNs t, PosedVehicle& posed) {
    if (posed.valid && posed.time_ns == t) {
      return;
    }
    posed.time_ns = t;
    posed.valid = true;
    posed.rotated = false;
    posed.pose = pose_at(v.trajectory, t);
  }

  // Intersects one vehicle at its pose; replaces `out` if the vehicle is nearer.
  void intersect_vehicle(const VehicleEntry& v, PosedVehicle& posed, const CheckedRay& ray,
                         RayHit& out) const {
    const Pose2& pose = posed.pose;
    const double limit = std::min(out.range, ray.max_range);
    const Eigen::Vector3d position(pose.x, pose.y, 0.0);
    // Bounding-sphere reject before any trigonometry: centred over the reference point, grown by the
    // bound centre's plan offset so that it holds for every yaw.
    const Eigen::Vector3d any_yaw_centre(pose.x, pose.y, v.bound_centre.z());
    if (!ray_meets_sphere(ray, any_yaw_centre, v.bound_radius + v.bound_centre.head<2>().norm(), limit)) {
      return;
    }
    if (!posed.rotated) {
      posed.rotation = Eigen::AngleAxisd(pose.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      posed.rotated = true;
    }
    const Eigen::Matrix3d& rotation = posed.rotation;
    const Eigen::Vector3d origin = rotation.transpose() * (ray.origin - position);
    const Eigen::Vector3d direction = rotation.transpose() * ray.direction;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    set_ray(rh, origin, direction, to_tfar(limit));
    rtcIntersect1(v.bvh.get(), &context, &rh);
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID && static_cast<double>(rh.ray.tfar) < limit) {
      out.range = static_cast<double>(rh.ray.tfar);
      out.normal = facing_normal(
          rotation * Eigen::Vector3f(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z).cast<double>(), ray.direction);
      out.surface = SurfaceClass::kVehicle;
      out.reflectivity = reflectivity[class_index(SurfaceClass::kVehicle)];
      out.vehicle_id = v.id;
    }
  }

  void static_batch_single(std::span<const CheckedRay> rays, std::span<RayHit> hits) const {
    for (std::size_t i = 0; i < rays.size(); ++i) {
      if (rays[i].valid) {
        intersect_static(rays[i], hits[i]);
      }
    }
  }

  void static_batch_packet16(std::span<const CheckedRay> rays, std::span<RayHit> hits) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    RTCRayHit16 packet;
    alignas(64) std::array<int, kPacketWidth> valid{};
    std::array<float, kPacketWidth> ground{};
    for (std::size_t base = 0; base < rays.size(); base += kPacketWidth) {
      const std::size_t n = std::min<std::size_t>(kPacketWidth, rays.size() - base);
      for (std::size_t k = 0; k < kPacketWidth; ++k) {
        const bool use = k < n && rays[base + k].valid;
        valid[k] = use ? -1 : 0;
        packet.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        if (!use) {
          continue;
        }
        const CheckedRay& r = rays[base + k];
        packet.ray.org_x[k] = static_cast<float>(r.origin.x());
        packet.ray.org_y[k] = static_cast<float>(r.origin.y());
        packet.ray.org_z[k] = static_cast<float>(r.origin.z());
        packet.ray.tnear[k] = 0.0F;
        packet.ray.dir_x[k] = static_cast<float>(r.direction.x());
        packet.ray.dir_y[k] = static_cast<float>(r.direction.y());
        packet.ray.dir_z[k] = static_cast<float>(r.direction.z());
        packet.ray.time[k] = 0.0F;
        ground[k] = ground_within(r);
        packet.ray.tfar[k] = std::min(to_tfar(r.max_range), ground[k]);
        packet.ray.mask[k] = 0xFFFFFFFFU;
        packet.ray.id[k] = static_cast<unsigned>(k);
        packet.ray.flags[k] = 0;
        packet.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
      }
      rtcIntersect16(valid.data(), static_scene.get(), &context, &packet);
      for (std::size_t k = 0; k < n; ++k) {
        if (valid[k] == 0) {
          continue;
        }
        if (packet.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID) {
          RTCHit h;
          h.Ng_x = packet.hit.Ng_x[k];
          h.Ng_y = packet.hit.Ng_y[k];
          h.Ng_z = packet.hit.Ng_z[k];
          h.geomID = packet.hit.geomID[k];
          finish_static_hit(h, packet.ray.tfar[k], rays[base + k].direction, hits[base + k]);
        } else if (std::isfinite(ground[k])) {
          finish_ground_hit(ground[k], rays[base + k].direction, hits[base + k]);
        }
      }
    }
  }

  // At most kChunk rays.
  void static_batch_stream(std::span<const CheckedRay> rays, std::span<RayHit> hits) const {
    std::array<RTCRayHit, kChunk> stream;
    std::array<float, kChunk> ground{};
    for (std::size_t i = 0; i < rays.size(); ++i) {
      // An invalid ray gets an empty interval (tfar < tnear), which Embree skips.
      ground[i] = rays[i].valid ? ground_within(rays[i]) : std::numeric_limits<float>::infinity();
      set_ray(stream[i], rays[i].valid ? rays[i].origin : Eigen::Vector3d::Zero(),
              rays[i].valid ? rays[i].direction : Eigen::Vector3d::UnitZ(),
              rays[i].valid ? std::min(to_tfar(rays[i].max_range), ground[i]) : -1.0F);
    }
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    rtcIntersect1M(static_scene.get(), &context, stream.data(), static_cast<unsigned>(rays.size()),
                   sizeof(RTCRayHit));
    for (std::size_t i = 0; i < rays.size(); ++i) {
      if (rays[i].valid && stream[i].hit.geomID != RTC_INVALID_GEOMETRY_ID) {
        finish_static_hit(stream[i].hit, stream[i].ray.tfar, rays[i].direction, hits[i]);
      } else if (rays[i].valid && std::isfinite(ground[i])) {
        finish_ground_hit(ground[i], rays[i].direction, hits[i]);
      }
    }
  }

  // cast_batch on the calling thread.
  void cast_rays(std::span<const Ray> rays, std::span<RayHit> hits) const {
    if (rays.empty()) {
      return;
    }
    TimeNs t_min = rays.front().time_ns;
    TimeNs t_max = t_min;
    for (const Ray& r : rays) {
      t_min = std::min(t_min, r.time_ns);
      t_max = std::max(t_max, r.time_ns);
    }
    // One sphere per vehicle bounding it wherever it is during the batch; only rays that meet it pay
    // for the exact pose at their own time.
    struct SweptSphere {
      Eigen::Vector3d centre;
      double radius;
      PosedVehicle posed;  // at the last ray's time that met the sphere
    };
    std::vector<SweptSphere> swept;
    swept.reserve(vehicles.size());
    for (const auto& v : vehicles) {
      const auto path = path_vertices(v.trajectory, t_min, t_max);
      Eigen::Vector2d mid = Eigen::Vector2d::Zero();
      for (const auto& p : path) {
        mid += p;
      }
      mid /= static_cast<double>(path.size());
      double spread = 0.0;
      for (const auto& p : path) {
        spread = std::max(spread, (p - mid).norm());
      }
      swept.push_back({Eigen::Vector3d(mid.x(), mid.y(), v.bound_centre.z()),
                       v.bound_radius + v.bound_centre.head<2>().norm() + spread,
                       {}});
    }
    std::array<CheckedRay, kChunk> checked;
    for (std::size_t base = 0; base < rays.size(); base += kChunk) {
      const std::size_t n = std::min(kChunk, rays.size() - base);
      const std::span<const CheckedRay> chunk(checked.data(), n);
      const std::span<RayHit> chunk_hits = hits.subspan(base, n);
      for (std::size_t i = 0; i < n; ++i) {
        const Ray& r = rays[base + i];
        check_ray(r.origin, r.direction, r.max_range, checked[i]);
        chunk_hits[i] = RayHit{};
      }
      switch (config.batch_mode) {
        case BatchMode::kPacket16:
          if (packet16_native) {
            static_batch_packet16(chunk, chunk_hits);
          } else {
            static_batch_single(chunk, chunk_hits);  // no native 16-wide packets in this build
          }
          break;
        case BatchMode::kStream:
          static_batch_stream(chunk, chunk_hits);
          break;
        case BatchMode::kSingle:
          static_batch_single(chunk, chunk_hits);
          break;
      }
      for (std::size_t j = 0; j < vehicles.size(); ++j) {
        const auto& v = vehicles[j];
        for (std::size_t i = 0; i < n; ++i) {
          const CheckedRay& ray = checked[i];
          if (ray.valid && ray_meets_sphere(ray, swept[j].centre, swept[j].radius,
                                            std::min(chunk_hits[i].range, ray.max_range))) {
            pose_vehicle(v, rays[base + i].time_ns, swept[j].posed);
            intersect_vehicle(v, swept[j].posed, ray, chunk_hits[i]);
          }
        }
      }
    }
  }
};

Raycaster::Raycaster(const Scene& scene, const RaycasterConfig& config) : impl_(std::make_unique<Impl>()) {
  require(config.cylinder_segments >= 3, "raycaster: cylinder_segments must be >= 3");
  require(config.sphere_subdivisions >= 0 && config.sphere_subdivisions <= 5,
          "raycaster: sphere_subdivisions must be in [0, 5]");
  impl_->config = config;
  impl_->device.reset(rtcNewDevice(config.embree_config.c_str()));
  if (!impl_->device) {
    throw std::runtime_error(std::string("Embree error during rtcNewDevice(\"") + config.embree_config +
                             "\"): " + error_name(rtcGetDeviceError(nullptr)));
  }
  rtcSetDeviceErrorFunction(impl_->device.get(), &Impl::on_error, impl_.get());
  impl_->packet16_native =
      rtcGetDeviceProperty(impl_->device.get(), RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0;
  const Reflectivity& r = scene.reflectivity;
  impl_->reflectivity[class_index(SurfaceClass::kGround)] = r.ground;
  impl_->reflectivity[class_index(SurfaceClass::kBuilding)] = r.building;
  impl_->reflectivity[class_index(SurfaceClass::kPole)] = r.pole;
  impl_->reflectivity[class_index(SurfaceClass::kVegetation)] = r.vegetation;
  impl_->reflectivity[class_index(SurfaceClass::kVehicle)] = r.vehicle;
  impl_->build_static(scene);
  impl_->build_vehicles(scene);
}

Raycaster::~Raycaster() = default;
Raycaster::Raycaster(Raycaster&&) noexcept = default;
Raycaster& Raycaster::operator=(Raycaster&&) noexcept = default;

std::size_t Raycaster::vehicle_count() const {
  return impl_->vehicles.size();
}

const TriangleMesh& Raycaster::vehicle_mesh(std::size_t index) const {
  return impl_->vehicles.at(index).mesh;
}

const TriangleMesh& Raycaster::static_mesh(SurfaceClass surface) const {
  return impl_->static_meshes.at(class_index(surface));
}

RayHit Raycaster::cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, TimeNs t,
                       double max_range) const {
  RayHit hit;
  CheckedRay ray;
  check_ray(origin, direction, max_range, ray);
  if (!ray.valid) {
    return hit;
  }
  impl_->intersect_static(ray, hit);
  for (const auto& v : impl_->vehicles) {
    Impl::PosedVehicle posed;
    Impl::pose_vehicle(v, t, posed);
    impl_->intersect_vehicle(v, posed, ray, hit);
  }
  return hit;
}

void Raycaster::cast_batch(std::span<const Ray> rays, std::span<RayHit> hits, int threads) const {
  if (rays.size() != hits.size()) {
    throw std::invalid_argument("Raycaster::cast_batch: rays and hits differ in size");
  }
  // Runs of whole 64-ray chunks from the batch's start: every ray shares its 16-ray Embree packet with
  // the same rays as on one thread (which of two faces meeting at an edge a packet reports may depend on
  // the packet), so the hits are the same bits whatever the thread count. Each run bounds the vehicles
  // over its own time span only.
  run_ranges_in_parallel((rays.size() + kChunk - 1) / kChunk, threads,
                         [&](std::size_t /*run*/, std::size_t begin, std::size_t end) {
                           const std::size_t first = begin * kChunk;
                           const std::size_t n = std::min(end * kChunk, rays.size()) - first;
                           impl_->cast_rays(rays.subspan(first, n), hits.subspan(first, n));
                         });
}

}  // namespace rsu::sim
