// SPDX-License-Identifier: Apache-2.0
#include "tools/rsu_calibrate/mount_calibration.h"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "common/symmetric_eigen.h"

namespace rsu::tools {

namespace {

using calibration::PlaneFit;
using calibration::PlaneMatch;

// One point per cell of the given size (the first in scan order): the fine stage's residuals stay single
// measurements, each with its own noise, and the ground near the pole does not outweigh the street.
std::vector<Eigen::Vector3d> thin_out(const std::vector<Eigen::Vector3d>& points, double cell_m,
                                      double min_range_m) {
  std::unordered_set<std::int64_t> taken;
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector3d& p : points) {
    const std::optional<std::int64_t> key = calibration::voxel_key(p, cell_m);
    if (!key || p.norm() < min_range_m)
      continue;
    if (taken.insert(*key).second)
      out.push_back(p);
  }
  return out;
}

class MapPlanes {
 public:
  MapPlanes(const std::vector<Eigen::Vector3f>& map, const Pose3& centre, double reach_m, int neighbours)
      : cloud_(pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>()), neighbours_(neighbours) {
    for (const Eigen::Vector3f& p : map)
      if (std::hypot(static_cast<double>(p.x()) - centre.x, static_cast<double>(p.y()) - centre.y) <= reach_m)
        cloud_->emplace_back(p.x(), p.y(), p.z());
    if (!cloud_->empty())
      tree_.setInputCloud(cloud_);
  }
  std::size_t size() const { return cloud_->size(); }

  // The background matched to the map's planes at `pose`: each point to the plane through its nearest
  // map points, if that is within max_distance_m and the neighbourhood is flat.
  std::vector<PlaneMatch> match(const std::vector<Eigen::Vector3d>& points, const Pose3& pose,
                                double max_distance_m, const CalibrationConfig& config) {
    const double min_cos_incidence = std::cos(deg_to_rad(config.max_incidence_deg));
    std::vector<PlaneMatch> matches;
    if (cloud_->size() < static_cast<std::size_t>(neighbours_))
      return matches;
    const Eigen::Isometry3d t = pose.to_isometry();
    std::vector<int> index(static_cast<std::size_t>(neighbours_));
    std::vector<float> distance2(static_cast<std::size_t>(neighbours_));
    for (const Eigen::Vector3d& p : points) {
      const Eigen::Vector3d a = t * p;
      const pcl::PointXYZ query(static_cast<float>(a.x()), static_cast<float>(a.y()),
                                static_cast<float>(a.z()));
      if (tree_.nearestKSearch(query, neighbours_, index, distance2) < neighbours_)
        continue;
      if (static_cast<double>(distance2[0]) > max_distance_m * max_distance_m)
        continue;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int i : index)
        mean += (*cloud_)[static_cast<std::size_t>(i)].getVector3fMap().cast<double>();
      mean /= static_cast<double>(index.size());
      Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
      for (int i : index) {
        const Eigen::Vector3d d =
            (*cloud_)[static_cast<std::size_t>(i)].getVector3fMap().cast<double>() - mean;
        scatter += d * d.transpose();
      }
      const SymmetricEigen3 eigen(scatter);
      const Eigen::Vector3d lambda = eigen.eigenvalues();  // ascending
      if (!(lambda[1] > 1e-6) || lambda[0] > config.max_plane_thickness * lambda[1])
        continue;  // an edge, a corner, a thin pole, a crown: no single plane
      const Eigen::Vector3d normal = eigen.eigenvectors().col(0).normalized();
      const Eigen::Vector3d beam = a - t.translation();
      const double range = beam.norm();
      const double cos_incidence = std::abs(normal.dot(beam)) / range;
      if (cos_incidence < min_cos_incidence)
        continue;
      const double sin2 = 1.0 - cos_incidence * cos_incidence;
      const double sigma =
          std::sqrt(config.range_sigma_m * config.range_sigma_m * cos_incidence * cos_incidence +
                    range * range * config.angle_sigma_rad * config.angle_sigma_rad * sin2);
      matches.push_back(PlaneMatch{p, mean, normal, sigma});
    }
    return matches;
  }

 private:
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud_;
  pcl::KdTreeFLANN<pcl::PointXYZ> tree_;
  int neighbours_;
};

}  // namespace

CalibrationResult calibrate_mount(const std::vector<Eigen::Vector3d>& background_sensor,
                                  const std::vector<Eigen::Vector3f>& map, const Pose3& initial,
                                  const CalibrationConfig& config) {
  CalibrationResult result;
  result.initial = initial;
  result.pose = initial;
  const std::vector<Eigen::Vector3d> points =
      thin_out(background_sensor, config.background_spacing_m, config.min_range_m);
  result.background_points = points.size();
  double reach = 0.0;
  for (const Eigen::Vector3d& p : points)
    reach = std::max(reach, p.head<2>().norm());

  // Coarse: the grid searches on an evenly spread subset.
  std::vector<Eigen::Vector3d> subset;
  const std::size_t stride =
      std::max<std::size_t>(1, points.size() / std::max<std::size_t>(1, config.search_points));
  for (std::size_t i = 0; i < points.size(); i += stride)
    subset.push_back(points[i]);
  const calibration::VoxelOccupancy coarse_map(map, config.coarse_voxel_m);
  result.search = calibration::search_pose(subset, coarse_map, initial, config.coarse);
  const calibration::VoxelOccupancy medium_map(map, config.medium_voxel_m);
  result.search = calibration::search_pose(subset, medium_map, result.search.pose, config.medium);
  result.coarse = result.search.pose;

  // Fine: point-to-plane, all six free, the match distance shrinking as the pose settles.
  const double margin = config.coarse.half_extent_m + config.match_distances_m.front() + 1.0;
  MapPlanes planes(map, initial, reach + margin, config.plane_neighbours);
  result.map_points = planes.size();
  Pose3 pose = result.coarse;
  for (const double distance : config.match_distances_m) {
    for (int i = 0; i < config.iterations_per_distance; ++i) {
      const PlaneFit fit =
          calibration::fit_planes(planes.match(points, pose, distance, config), pose, config.huber_sigmas);
      ++result.iterations;
      pose = calibration::apply_step(pose, fit.step);
      if (fit.step.head<3>().norm() < 1e-5 && fit.step.tail<3>().norm() < 1e-7)
        break;
    }
  }
  result.pose = pose;
  // The information at the solution, from the last distance's matches.
  result.fit = calibration::fit_planes(planes.match(points, pose, config.match_distances_m.back(), config),
                                       pose, config.huber_sigmas);
  result.uncertainty = calibration::mount_uncertainty(result.fit, pose, config.floor);
  result.verdict = calibration::judge(result.fit, result.uncertainty, config.limits);
  return result;
}

}  // namespace rsu::tools
