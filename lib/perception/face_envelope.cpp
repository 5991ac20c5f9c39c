// SPDX-License-Identifier: Apache-2.0
#include "perception/face_envelope.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <vector>

namespace rsu::perception {
namespace {

// Beyond 9 sigma the normal's tails are below 1e-18 of its mass: taken as 0 and 1 without erfc and exp,
// which most of a face's points (metres from it, sigma centimetres) are (issue 16: the dense frame).
constexpr double kTail = 9.0;

double normal_cdf(double x) {
  if (x > kTail)
    return 1.0;
  if (x < -kTail)
    return 0.0;
  return 0.5 * std::erfc(-x / std::numbers::sqrt2);
}

double normal_pdf(double x, double sigma) {
  if (std::abs(x) > kTail * sigma)
    return 0.0;
  return std::exp(-0.5 * x * x / (sigma * sigma)) / (sigma * std::sqrt(2.0 * std::numbers::pi));
}

}  // namespace

FaceEnvelope outer_envelope(std::span<const double> s, double noise_sigma, double band) {
  FaceEnvelope out;
  if (s.empty())
    return out;
  const double sigma = std::max(noise_sigma, 1e-4);
  band = std::max(band, 4.0 * sigma);
  // Start near the outside: the 90th percentile, inside the few stray returns beyond it.
  std::vector<double> sorted(s.begin(), s.end());
  std::sort(sorted.begin(), sorted.end());
  double f = sorted[static_cast<std::size_t>(0.9 * static_cast<double>(sorted.size() - 1))];
  double face_weight = 0.5;
  constexpr double kStray = 0.02;  // share of returns outside the face (spray, a mirror's edge)
  // A point's share of the face is face / (face + ...), and face is 0 beyond kTail sigma of f: only the
  // points within that window of the sorted coordinates add to the sums (a near car on a dense sensor
  // gives a face thousands of points, most of them inside the body, metres from it).
  double n_face = 0.0;
  for (int iteration = 0; iteration < 30; ++iteration) {
    double sum_r = 0.0, sum_rs = 0.0;
    const auto first = std::lower_bound(sorted.begin(), sorted.end(), f - kTail * sigma);
    const auto last = std::upper_bound(first, sorted.end(), f + kTail * sigma);
    for (auto it = first; it != last; ++it) {
      const double si = *it;
      const double face = face_weight * normal_pdf(si - f, sigma);
      // Behind the face: uniform over [f - band, f], blurred by the same noise.
      const double inside = (1.0 - face_weight - kStray) / band *
                            (normal_cdf((f - si) / sigma) - normal_cdf((f - band - si) / sigma));
      const double stray = kStray / (2.0 * band);
      const double r = face / (face + inside + stray);
      sum_r += r;
      sum_rs += r * si;
    }
    n_face = sum_r;
    if (!(sum_r > 1e-9))
      break;
    const double next = sum_rs / sum_r;
    face_weight = std::clamp(sum_r / static_cast<double>(s.size()), 0.05, 1.0 - kStray - 0.01);
    const bool converged = std::abs(next - f) < 1e-5;
    f = next;
    if (converged)
      break;
  }
  out.position = f;
  out.face_points = n_face;
  out.sigma = sigma / std::sqrt(std::max(n_face, 1.0));
  return out;
}

FaceEnvelope FaceEnvelopeMemo::operator()(std::span<const double> s, double noise_sigma, double band) {
  const auto same = [&](const Entry& e) {
    return e.noise_sigma == noise_sigma && e.band == band && e.s.size() == s.size() &&
           (s.empty() || std::memcmp(e.s.data(), s.data(), s.size_bytes()) == 0);
  };
  if (const auto it = std::find_if(entries_.begin(), entries_.end(), same); it != entries_.end())
    return it->envelope;
  const FaceEnvelope envelope = outer_envelope(s, noise_sigma, band);
  entries_.push_back({{s.begin(), s.end()}, noise_sigma, band, envelope});
  return envelope;
}

}  // namespace rsu::perception
