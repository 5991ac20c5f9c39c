// SPDX-License-Identifier: Apache-2.0
// Ray casting against a Scene with Embree 3: one BVH for everything static but the ground (buildings,
// poles, trees, shrubs) in the map frame, and one BVH per vehicle in the vehicle's own frame. The
// ground, the plane z = 0 within its half extent, is intersected directly and bounds the BVH search.
//
// Motion: a spinning LiDAR fires each laser at its own time, so a moving vehicle is seen at a
// different pose by every ray (the rolling-shutter skew of a real sweep). Each ray is therefore
// transformed into a vehicle's frame at pose_at(trajectory, ray time) and intersected there; the
// nearest of the static and vehicle hits wins.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <string>

#include <Eigen/Core>

#include "common/time.h"
#include "sim/mesh.h"
#include "sim/scene.h"

namespace rsu::sim {

// What a ray hit; the static classes carry the reflectivity of sim/scene.h's Reflectivity.
enum class SurfaceClass : std::uint8_t { kNone = 0, kGround, kBuilding, kPole, kVegetation, kVehicle };

const char* to_string(SurfaceClass surface);

struct RayHit {
  double range = std::numeric_limits<double>::infinity();  // along the unit ray direction, m
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();        // unit, map frame, facing the ray origin
  double reflectivity = 0.0;
  SurfaceClass surface = SurfaceClass::kNone;
  std::uint32_t vehicle_id = 0;  // Vehicle::id when surface == kVehicle

  bool hit() const { return surface != SurfaceClass::kNone; }
};

// One query for the batched path.
struct Ray {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();      // map frame
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();  // unit, map frame
  TimeNs time_ns = 0;
  double max_range = std::numeric_limits<double>::infinity();
};

// How cast_batch hands the static scene to Embree. Measured on the corridor scenario (bench/sim,
// VLP-32C rays ordered by elevation within each packet): rtcIntersect16 and rtcIntersect1M both
// about 3x rtcIntersect1; with rays in channel order only about 1.7x, so callers should keep
// neighbouring beams adjacent, as LidarSimulator does.
enum class BatchMode : std::uint8_t {
  kSingle,    // rtcIntersect1 per ray
  kPacket16,  // rtcIntersect16 over groups of 16 rays
  kStream,    // rtcIntersect1M with the coherent-rays hint
};

struct RaycasterConfig {
  int cylinder_segments = 16;   // poles, trunks, lamp arms
  int sphere_subdivisions = 2;  // tree crowns and shrubs: 320 triangles each
  BatchMode batch_mode = BatchMode::kPacket16;
  // Embree's robust mode: no rays slipping between triangles that share an edge (a box's corner, a
  // cylinder's seams; the ground, whose diagonal ran under the sensor, is no longer triangles).
  bool robust_traversal = true;
  // One build thread: scene builds are small (milliseconds), and a single-threaded build keeps the
  // BVH, hence ties between equidistant hits, identical from run to run on a shared 2-core machine.
  std::string embree_config = "threads=1";
};

// Errors from Embree (device creation, geometry or scene build) are thrown as std::runtime_error
// with Embree's error code and message; invalid scene content as std::invalid_argument naming the
// object (e.g. "building 3: length must be positive and finite").
class Raycaster {
 public:
  explicit Raycaster(const Scene& scene, const RaycasterConfig& config = {});
  ~Raycaster();
  Raycaster(Raycaster&&) noexcept;
  Raycaster& operator=(Raycaster&&) noexcept;
  Raycaster(const Raycaster&) = delete;
  Raycaster& operator=(const Raycaster&) = delete;

  // Nearest hit along origin + s * direction, 0 < s <= max_range, everything posed at time t.
  // A non-finite or zero-length input gives no hit. Thread-safe (const).
  RayHit cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, TimeNs t,
              double max_range = std::numeric_limits<double>::infinity()) const;

  // Same results as cast() for each ray (hits.size() must equal rays.size()), faster for many rays
  // that are close in time: the vehicles' swept bounding spheres are computed once per call.
  // threads > 1 casts runs of the batch on that many threads, the caller's among them, with the same
  // hits, bit for bit, as on one; threads start per call, so this pays for a frame's rays, not a
  // packet's. Throws std::invalid_argument for threads < 1.
  void cast_batch(std::span<const Ray> rays, std::span<RayHit> hits, int threads = 1) const;

  std::size_t vehicle_count() const;
  // The vehicle's mesh in its own frame, as it was put in the BVH.
  const TriangleMesh& vehicle_mesh(std::size_t index) const;
  // The static scene's mesh for one class (ground, building, pole or vegetation), map frame.
  const TriangleMesh& static_mesh(SurfaceClass surface) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rsu::sim
