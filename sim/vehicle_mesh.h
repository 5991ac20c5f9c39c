// SPDX-License-Identifier: Apache-2.0
// A passenger-car-shaped closed mesh built from VehicleShape (sim/scene.h).
//
// Why not a box: the paper's L-shape fitting and size correction (Algorithm 1) are sensitive to what
// the LiDAR actually sees of a car: rounded plan-view corners pull points inward near the corners,
// the glasshouse is narrower than the body, low rays hit the tyres through the wheel arches, and
// mirrors stick out at the belt line. The footprint (plan-view bounding rectangle) is still exactly
// length x width so that the ground truth the V2I announcement carries matches the mesh.
#pragma once

#include "sim/mesh.h"
#include "sim/scene.h"

namespace rsu::sim {

// Vehicle frame: origin at the footprint centre on the ground, +x forward, +y left, z up.
// Components (each closed, outward-facing; they overlap where they touch):
//   lower body  ground_clearance .. belt_height, rounded rectangle length x width; below the wheel
//               arch tops the sides are cut back around the wheels (wheel arches);
//   glasshouse  belt_height .. height, inset by cabin_inset each side, its roof outline shortened by
//               windscreen_run at the front and rear_slope_run at the back (sloped windscreen and
//               rear window); the hood is the body top ahead of the windscreen base;
//   wheels      four cylinders along y, centres at x = +/- wheelbase / 2, z = wheel_radius, their
//               outer faces slightly inboard of the body sides;
//   mirrors     two boxes at the belt line sticking out of the glasshouse, inside the width.
// Throws std::invalid_argument naming the offending field if the proportions are inconsistent.
TriangleMesh make_vehicle_mesh(const VehicleShape& shape);

// The same checks make_vehicle_mesh runs; throws std::invalid_argument("vehicle shape: <field> ...").
void validate_vehicle_shape(const VehicleShape& shape);

}  // namespace rsu::sim
