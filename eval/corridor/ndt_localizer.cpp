#include "eval/corridor/ndt_localizer.h"

#include <pcl/filters/random_sample.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/ndt.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

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
double horizontal_degeneracy(const Eigen::Matrix<double, 6, 6>& hessian) {
  const Eigen::Matrix2d information = -hessian.topLeftCorner<2, 2>();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(information);
  const double weakest = eigen.eigenvalues().minCoeff();
  const double strongest = eigen.eigenvalues().maxCoeff();
  if (eigen.info() != Eigen::Success || !(weakest > 0.0)) {
    return std::numeric_limits<double>::infinity();  // no curvature at all along some direction
  }
  return std::sqrt(strongest / weakest);
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
    const double px = p.x, py = p.y;
    const double r2 = px * px + py * py;
    if (r2 < config_.self_filter_radius_m * config_.self_filter_radius_m)
      continue;
    const Eigen::Vector3d v = sensor_to_vehicle * Eigen::Vector3d(p.x, p.y, p.z);
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
  result.degeneracy = horizontal_degeneracy(impl_->ndt.hessian_at(aligned));
  result.pose = Pose2{t(0, 3), t(1, 3), std::atan2(t(1, 0), t(0, 0))};
  result.covariance.diagonal() << config_.output_sigma_xy_m * config_.output_sigma_xy_m,
      config_.output_sigma_xy_m * config_.output_sigma_xy_m,
      config_.output_sigma_yaw_rad * config_.output_sigma_yaw_rad;
  return result;
}

}  // namespace rsu::eval
