// SPDX-License-Identifier: Apache-2.0
// A point-cloud map of the static scene for NDT (paper Sec. 4.1 used Tier IV's HD point-cloud map of the
// digital twin): the static surfaces' triangles sampled uniformly by area, seeded.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "sim/mesh.h"
#include "sim/raycaster.h"

namespace rsu::eval {

// About one point per spacing^2 of surface; every triangle gets at least one point if it is larger than
// half a cell.
std::vector<Eigen::Vector3f> sample_surface(const sim::TriangleMesh& mesh, double spacing_m,
                                            std::uint64_t seed);

// The street's map: every static surface (ground, buildings, poles, vegetation; not the vehicles), the
// ground at twice the spacing (it is most of the area and carries the least).
std::vector<Eigen::Vector3f> sample_static_map(const sim::Raycaster& raycaster, double spacing_m,
                                               std::uint64_t seed);

}  // namespace rsu::eval
