// SPDX-License-Identifier: Apache-2.0
#include "eval/corridor/ndt_localizer.h"

#include <pcl/filters/random_sample.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/ndt.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "common/symmetric_eigen.h"
#include "fusion/covariance_floor.h"
#include "lidar/point_eigen.h"

namespace rsu::eval {

namespace {

// PCL's NDT with the Hessian of its score at the solution exposed (protected in PCL 1.13). Evaluated
// after align() on the aligned scan, it reuses the angular derivatives of the last step's transform.
class NdtWithHessian : public pcl::NormalDistributionsTransform<pcl::PointXYZ, pcl::PointXYZ> {
 public:
  Eigen::Matrix<double, 6, 6> hessian_at(const pcl::PointCloud<pcl::PointXYZ>& aligned) {
    Eigen::Matrix<double, 6, 6> hessian;
    computeHessian(hessian, aligned);
    return hessian;
  }
};

// How much worse the match constrains the vehicle in its weakest horizontal direction than in its
// strongest: sqrt(lambda_max / lambda_min) of the score's curvature in x, y (the information -H, the
// inverse of a Laplace covariance). 1: equally well both ways; a street with nothing along it: large.
// Also the direction of that weakest hold (rad, map frame, modulo pi): the eigenvector of the smallest
// eigenvalue (SelfAdjointEigenSolver sorts them in increasing order).
struct HorizontalHold {
  double degeneracy = std::numeric_limits<double>::infinity();
  double weak_axis_rad = 0.0;
};

HorizontalHold horizontal_hold(const Eigen::Matrix<double, 6, 6>& hessian) {
  const Eigen::Matrix2d information = -hessian.topLeftCorner<2, 2>();
  const SymmetricEigen2 eigen(information);
  HorizontalHold hold;
  if (eigen.info() != Eigen::Success) {
    return hold;
  }
  const Eigen::Vector2d weak = eigen.eigenvectors().col(0);
  hold.weak_axis_rad = std::atan2(weak.y(), weak.x());
  const double weakest = eigen.eigenvalues()(0);
  const double strongest = eigen.eigenvalues()(1);
  if (weakest > 0.0) {
    hold.degeneracy = std::sqrt(strongest / weakest);
  }  // else no curvature at all along some direction: infinite
  return hold;
}

// Autoware's LAPLACE_APPROXIMATION: the score near its maximum as a Gaussian, whose covariance is the
// inverse of the information -H. Over all six parameters (x, y, z, roll, pitch, yaw: PCL's order), then
// the (x, y, yaw) marginal, so that what z and tilt leave open counts too; where the six are not all
// curved (a saddle in tilt), the (x, y, yaw) block alone, or the (x, y) block alone (Autoware's). Empty
// when the match has no curvature along some horizontal direction.
template <int N>
std::optional<Eigen::Matrix<double, N, N>> inverse_information(const Eigen::Matrix<double, N, N>& hessian) {
  const Eigen::Matrix<double, N, N> information = -0.5 * (hessian + hessian.transpose());
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt(information);
  if (llt.info() != Eigen::Success) {
    return std::nullopt;
  }
  const Eigen::Matrix<double, N, N> covariance = llt.solve(Eigen::Matrix<double, N, N>::Identity());
  return covariance.allFinite() ? std::optional<Eigen::Matrix<double, N, N>>(covariance) : std::nullopt;
}

std::optional<Eigen::Matrix3d> laplace_covariance(const Eigen::Matrix<double, 6, 6>& hessian,
                                                  double fallback_yaw_variance) {
  constexpr int kIndex[3] = {0, 1, 5};  // x, y, yaw
  Eigen::Matrix3d block;
  const auto full = inverse_information<6>(hessian);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      block(i, j) = full ? (*full)(kIndex[i], kIndex[j]) : hessian(kIndex[i], kIndex[j]);
    }
  }
  if (full) {
    return block;
  }
  if (const auto xy_yaw = inverse_information<3>(block)) {
    return xy_yaw;
  }
  // Not even curved in yaw: the (x, y) block alone (Autoware's), the yaw at the fixed figure (scaled as
  // the rest).
  const auto xy = inverse_information<2>(Eigen::Matrix2d(hessian.topLeftCorner<2, 2>()));
  if (!xy) {
    return std::nullopt;
  }
  Eigen::Matrix3d out = Eigen::Matrix3d::Zero();
  out.topLeftCorner<2, 2>() = *xy;
  out(2, 2) = fallback_yaw_variance;
  return out;
}

}  // namespace

struct NdtLocalizer::Impl {
  NdtWithHessian ndt;
  std::uint64_t seed = 0;
  std::uint64_t scans = 0;
};

NdtLocalizer::NdtLocalizer(const NdtConfig& config, const std::vector<Eigen::Vector3f>& map_points,
                           std::uint64_t seed)
    : config_(config), impl_(std::make_unique<Impl>()) {
  impl_->seed = seed;
  auto map = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  map->reserve(map_points.size());
  for (const auto& p : map_points)
    map->emplace_back(p.x(), p.y(), p.z());
  impl_->ndt.setResolution(static_cast<float>(config.resolution_m));
  impl_->ndt.setStepSize(config.step_size_m);
  // Autoware's ndt_scan_matcher stops when a Newton step is shorter than trans_epsilon (a length, m).
  // PCL 1.13 compares the SQUARED translation of the step with its epsilon, and its steps are capped at
  // the step size (0.1 m): given 0.01 directly, every first step would count as converged. The same
  // criterion in PCL's terms is epsilon^2.
  impl_->ndt.setTransformationEpsilon(config.transformation_epsilon * config.transformation_epsilon);
  impl_->ndt.setMaximumIterations(config.max_iterations);
  impl_->ndt.setInputTarget(map);
}

NdtLocalizer::~NdtLocalizer() = default;

NdtResult NdtLocalizer::align(const std::vector<lidar::LidarPoint>& scan, const Pose3& sensor_in_vehicle,
                              const Pose2& guess) {
  // Scan into the vehicle frame, cropped to the measurement range, the vehicle itself left out.
  const Eigen::Isometry3d sensor_to_vehicle = sensor_in_vehicle.to_isometry();
  auto cropped = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  cropped->reserve(scan.size());
  for (const lidar::LidarPoint& p : scan) {
    const double px = static_cast<double>(p.x), py = static_cast<double>(p.y);
    const double r2 = px * px + py * py;
    if (r2 < config_.self_filter_radius_m * config_.self_filter_radius_m)
      continue;
    const Eigen::Vector3d v = sensor_to_vehicle * lidar::position_of(p);
    if (std::abs(v.x()) > config_.crop_range_m || std::abs(v.y()) > config_.crop_range_m)
      continue;
    cropped->emplace_back(static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z()));
  }
  auto voxelized = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  const auto leaf = static_cast<float>(config_.voxel_leaf_m);
  grid.setLeafSize(leaf, leaf, leaf);
  grid.setInputCloud(cropped);
  grid.filter(*voxelized);
  auto sampled = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  if (static_cast<int>(voxelized->size()) > config_.random_sample_points) {
    pcl::RandomSample<pcl::PointXYZ> sample;
    sample.setSample(static_cast<unsigned int>(config_.random_sample_points));
    // Reproducible: the seed of each scan follows from the experiment's seed and the scan count.
    sample.setSeed(static_cast<unsigned int>((impl_->seed * 1000003ULL + impl_->scans) & 0x7fffffffULL));
    sample.setInputCloud(voxelized);
    sample.filter(*sampled);
  } else {
    sampled = voxelized;
  }
  ++impl_->scans;

  NdtResult result;
  result.scan_points = sampled->size();
  Eigen::Matrix4f initial = Eigen::Matrix4f::Identity();
  initial.topLeftCorner<2, 2>() << static_cast<float>(std::cos(guess.yaw)),
      static_cast<float>(-std::sin(guess.yaw)), static_cast<float>(std::sin(guess.yaw)),
      static_cast<float>(std::cos(guess.yaw));
  initial(0, 3) = static_cast<float>(guess.x);
  initial(1, 3) = static_cast<float>(guess.y);
  if (sampled->empty()) {
    result.pose = guess;
    return result;
  }
  impl_->ndt.setInputSource(sampled);
  pcl::PointCloud<pcl::PointXYZ> aligned;
  impl_->ndt.align(aligned, initial);
  const Eigen::Matrix4f t = impl_->ndt.getFinalTransformation();
  result.iterations = impl_->ndt.getFinalNumIteration();
  result.converged = impl_->ndt.hasConverged() && result.iterations < config_.max_iterations;
  result.fitness = impl_->ndt.getFitnessScore();
  const Eigen::Matrix<double, 6, 6> hessian = impl_->ndt.hessian_at(aligned);
  const HorizontalHold hold = horizontal_hold(hessian);
  result.degeneracy = hold.degeneracy;
  result.weak_axis_rad = hold.weak_axis_rad;
  const Eigen::Matrix4d td = t.cast<double>();
  result.pose = Pose2{td(0, 3), td(1, 3), std::atan2(td(1, 0), td(0, 0))};
  result.fixed_covariance.diagonal() << config_.output_sigma_xy_m * config_.output_sigma_xy_m,
      config_.output_sigma_xy_m * config_.output_sigma_xy_m,
      config_.output_sigma_yaw_rad * config_.output_sigma_yaw_rad;
  result.covariance = result.fixed_covariance;
  if (config_.covariance_estimate == NdtConfig::CovarianceEstimate::kLaplace) {
    // No curvature along some direction: the match knows nothing there (a huge variance, not the fixed one).
    constexpr double kNoInformationVariance = 1e4;
    const auto laplace = laplace_covariance(hessian, result.fixed_covariance(2, 2));
    result.covariance = laplace ? Eigen::Matrix3d(config_.laplace_scale * *laplace)
                                : Eigen::Matrix3d(Eigen::Matrix3d::Identity() * kNoInformationVariance);
    fusion::raise_to_floor(result.covariance, config_.laplace_min_sigma_xy_m,
                           config_.laplace_min_sigma_yaw_rad);
    const double excess = std::max(0.0, result.fitness - config_.fitness_nominal_m2);
    const double sigma_xy = config_.fitness_sigma_m_per_m2 * excess;
    const double sigma_yaw = config_.fitness_sigma_rad_per_m2 * excess;
    result.covariance.diagonal() +=
        Eigen::Vector3d(sigma_xy * sigma_xy, sigma_xy * sigma_xy, sigma_yaw * sigma_yaw);
  }
  return result;
}

}  // namespace rsu::eval
