// SPDX-License-Identifier: Apache-2.0
#include "perception/face_envelope.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <utility>
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

// s in ascending order (the EM sums over them in this order): a near car's face has thousands of points,
// sorted by a radix sort on the doubles' bits (std::sort's order for finite values, ~2x faster there).
std::vector<double> sorted_copy(std::span<const double> s) {
  if (s.size() < 256) {  // where the radix sort's passes over its buckets cost more than the sort
    std::vector<double> out(s.begin(), s.end());
    std::sort(out.begin(), out.end());
    return out;
  }
  const auto key = [](double v) {
    const auto bits = std::bit_cast<std::uint64_t>(v);
    return (bits >> 63) != 0 ? ~bits : bits | (std::uint64_t{1} << 63);
  };
  std::vector<std::uint64_t> keys(s.size()), scratch(s.size());
  for (std::size_t i = 0; i < s.size(); ++i)
    keys[i] = key(s[i]);
  constexpr int kBits = 11;
  constexpr std::size_t kBuckets = std::size_t{1} << kBits;
  std::vector<std::size_t> count(kBuckets);
  for (int shift = 0; shift < 64; shift += kBits) {
    std::fill(count.begin(), count.end(), 0);
    for (const std::uint64_t k : keys)
      ++count[(k >> shift) & (kBuckets - 1)];
    if (count[(keys.empty() ? 0 : keys[0] >> shift) & (kBuckets - 1)] == keys.size())
      continue;  // every key has this digit
    std::size_t sum = 0;
    for (std::size_t& c : count)
      sum += std::exchange(c, sum);
    for (const std::uint64_t k : keys)
      scratch[count[(k >> shift) & (kBuckets - 1)]++] = k;
    keys.swap(scratch);
  }
  std::vector<double> out(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    const std::uint64_t k = keys[i];
    out[i] = std::bit_cast<double>((k >> 63) != 0 ? k & ~(std::uint64_t{1} << 63) : ~k);
  }
  return out;
}

}  // namespace

FaceEnvelope outer_envelope(std::span<const double> s, double noise_sigma, double band) {
  FaceEnvelope out;
  if (s.empty())
    return out;
  const double sigma = std::max(noise_sigma, 1e-4);
  band = std::max(band, 4.0 * sigma);
  // Start near the outside: the 90th percentile, inside the few stray returns beyond it.
  std::vector<double> sorted = sorted_copy(s);
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
