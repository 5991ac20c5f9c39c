// SPDX-License-Identifier: Apache-2.0
// The tests' own copy of the published sensor tables (docs/design.md §2), independent of the library's.
#pragma once

#include <array>

namespace rsu::lidar::test {

constexpr std::array<double, 16> kVlp16ElevationDeg = {-15, 1, -13, 3,  -11, 5,  -9, 7,
                                                       -7,  9, -5,  11, -3,  13, -1, 15};

constexpr std::array<double, 32> kVlp32cElevationDeg = {
    -25,    -1,     -1.667, -15.639, -11.31, 0,      -0.667, -8.843, -7.254, 0.333,  -0.333,
    -6.148, -5.333, 1.333,  0.667,   -4,     -4.667, 1.667,  1,      -3.667, -3.333, 3.333,
    2.333,  -2.667, -3,     7,       4.667,  -2.333, -2,     15,     10.333, -1.333};

// `rot_correction` of the Velodyne calibration files (VLP32.yaml of the ROS velodyne and nebula drivers,
// in degrees), which the drivers SUBTRACT from the block azimuth: the manual's azimuth offset is its
// negation.
constexpr std::array<double, 32> kVlp32cRotCorrectionDeg = {
    -1.4, 4.2, -1.4, 1.4, -1.4, 1.4, -4.2, 1.4, -1.4, 4.2, -1.4, 1.4, -4.2, 1.4, -4.2, 1.4,
    -1.4, 4.2, -1.4, 4.2, -4.2, 1.4, -1.4, 1.4, -1.4, 1.4, -1.4, 4.2, -4.2, 1.4, -1.4, 1.4};

// HDL-32E, firing order (user manual 63-9113; the drivers' HDL32.yaml).
constexpr std::array<double, 32> kHdl32eElevationDeg = {
    -30.67, -9.33,  -29.33, -8.00,  -28.00, -6.67,  -26.67, -5.33,  -25.33, -4.00,  -24.00,
    -2.67,  -22.67, -1.33,  -21.33, 0.00,   -20.00, 1.33,   -18.67, 2.67,   -17.33, 4.00,
    -16.00, 5.33,   -14.67, 6.67,   -13.33, 8.00,   -12.00, 9.33,   -10.67, 10.67};

constexpr double kSequenceUs = 55.296;
constexpr double kFiringIntervalUs = 2.304;

}  // namespace rsu::lidar::test
