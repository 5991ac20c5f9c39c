// SPDX-License-Identifier: Apache-2.0
#include "eval/corridor/map_sampling.h"

#include <cmath>

#include "common/random.h"

namespace rsu::eval {

std::vector<Eigen::Vector3f> sample_surface(const sim::TriangleMesh& mesh, double spacing_m,
                                            std::uint64_t seed) {
  std::vector<Eigen::Vector3f> out;
  const double cell = spacing_m * spacing_m;
  std::uint64_t counter = 0;
  for (const Eigen::Vector3i& tri : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[static_cast<std::size_t>(tri.x())].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[static_cast<std::size_t>(tri.y())].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[static_cast<std::size_t>(tri.z())].cast<double>();
    const double area = 0.5 * (b - a).cross(c - a).norm();
    // Expected count area / cell; the fractional part decides one more point, so small triangles are
    // represented in proportion to their area.
    const double expected = area / cell;
    auto n = static_cast<std::uint64_t>(std::floor(expected));
    if (uniform_open01(mix64(seed ^ mix64(++counter))) < expected - std::floor(expected))
      ++n;
    for (std::uint64_t i = 0; i < n; ++i) {
      // Uniform in the triangle: reflect (u, v) back into it when u + v > 1.
      double u = uniform_open01(mix64(seed ^ mix64(++counter)));
      double v = uniform_open01(mix64(seed ^ mix64(++counter)));
      if (u + v > 1.0) {
        u = 1.0 - u;
        v = 1.0 - v;
      }
      out.push_back((a + u * (b - a) + v * (c - a)).cast<float>());
    }
  }
  return out;
}

std::vector<Eigen::Vector3f> sample_static_map(const sim::Raycaster& raycaster, double spacing_m,
                                               std::uint64_t seed) {
  std::vector<Eigen::Vector3f> map;
  for (auto surface : {sim::SurfaceClass::kGround, sim::SurfaceClass::kBuilding, sim::SurfaceClass::kPole,
                       sim::SurfaceClass::kVegetation}) {
    const auto part = sample_surface(raycaster.static_mesh(surface),
                                     surface == sim::SurfaceClass::kGround ? 2 * spacing_m : spacing_m,
                                     seed + static_cast<std::uint64_t>(surface));
    map.insert(map.end(), part.begin(), part.end());
  }
  return map;
}

}  // namespace rsu::eval
