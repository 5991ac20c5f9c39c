// SPDX-License-Identifier: Apache-2.0
// Where a vehicle's face is, from the points near it: its outer envelope, not their median.
//
// A face of the body (a door, a bumper) is its outermost surface there; what else the LiDAR hits near it
// lies inside it: the glasshouse above the belt line, tyres in their arches, the rounded corners, the
// interior edge of a hood or roof. So the points' coordinates s along the face's outward normal come
// from a mixture: the face itself, s ~ N(f, sigma^2) (sigma: the points' noise across the face), and
// parts of the body behind it, uniform over a band [f - band, f] (seen through the same noise); nothing
// lies outside but a few stray returns. The estimate of f maximises that mixture's likelihood (EM),
// which the median of the points (biased inwards by every point inside) does not.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace rsu::perception {

struct FaceEnvelope {
  double position = 0.0;     // f, along the outward normal
  double sigma = 0.0;        // standard error of f from the points' noise
  double face_points = 0.0;  // how many points the estimate attributes to the face itself
};

// s: the points' coordinates along the face's outward normal (at least one); noise_sigma: their noise
// across the face (> 0); band: how far inside the face other parts of the body may be counted.
FaceEnvelope outer_envelope(std::span<const double> s, double noise_sigma, double band);

// outer_envelope of inputs seen before, from the earlier result: one correction places the box in the
// same frame more than once (both length/width hypotheses, then the chosen box along the same axes), and
// a face's points are then the same, bit for bit; its EM is half of a near car's fix (issue 16). Inputs
// are compared exactly, so the result is the one outer_envelope gives.
class FaceEnvelopeMemo {
 public:
  FaceEnvelope operator()(std::span<const double> s, double noise_sigma, double band);

 private:
  struct Entry {
    std::vector<double> s;
    double noise_sigma = 0.0;
    double band = 0.0;
    FaceEnvelope envelope;
  };
  std::vector<Entry> entries_;
};

}  // namespace rsu::perception
