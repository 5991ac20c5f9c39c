// SPDX-License-Identifier: Apache-2.0
// The sim tests' busy street: every kind of static object and vehicles moving during a rotation, so a
// test of casting covers the BVH, the ground plane and the posed vehicles together.
#pragma once

#include "sim/scene.h"

namespace rsu::sim::testing {

// Facades, lamps and trees along a road on a 200 m ground, a car driving past the origin at 3 m around
// t = 0.5 s and one spinning on the spot 4 m away.
inline Scene street_with_traffic() {
  Scene scene;
  scene.ground.half_extent_m = 200.0;
  for (int i = 0; i < 6; ++i) {
    Building b;
    b.x = -30.0 + 12.0 * i;
    b.y = 15.0;
    scene.buildings.push_back(b);
    Pole p;
    p.x = -30.0 + 12.0 * i;
    p.y = 6.0;
    p.arm_length = 2.0;
    p.arm_yaw = -1.57;
    scene.poles.push_back(p);
    Tree t;
    t.x = -25.0 + 12.0 * i;
    t.y = -8.0;
    scene.trees.push_back(t);
  }
  Vehicle moving;
  moving.id = 1;
  Waypoints w;
  w.points = {{0, {-10.0, 3.0, 0.0}}, {1'000'000'000, {10.0, 3.0, 0.2}}};
  moving.trajectory = w;
  scene.vehicles.push_back(moving);
  Vehicle spinning;
  spinning.id = 2;
  Spin s;
  s.x = 4.0;
  s.y = -4.0;
  s.rate_rad_s = 3.0;
  spinning.trajectory = s;
  scene.vehicles.push_back(spinning);
  return scene;
}

}  // namespace rsu::sim::testing
