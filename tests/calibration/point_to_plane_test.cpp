// SPDX-License-Identifier: Apache-2.0
// The mount calibration's fine stage on its own: the perturbation's composition (apply_step), the angles
// of a rotation, the Jacobian that carries a covariance to the mount's parameters, and one Gauss-Newton
// step on point-to-plane residuals, each against what the test computes independently (Eigen's rotations,
// central differences, the residual's definition).
#include "calibration/point_to_plane.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "common/angles.h"
#include "common/pose.h"

namespace rsu::calibration {
namespace {

Eigen::Matrix3d rotation(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Vector6d parameters(const Pose3& p) {
  Vector6d v;
  v << p.x, p.y, p.z, p.roll, p.pitch, p.yaw;
  return v;
}

TEST(PointToPlane, RollPitchYawRecoversTheAngles) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> any(-3.1, 3.1);
  std::uniform_real_distribution<double> pitch(-1.5, 1.5);  // away from the +-90 deg singularity
  for (int i = 0; i < 200; ++i) {
    const double r = any(rng), p = pitch(rng), y = any(rng);
    const Eigen::Vector3d rpy = roll_pitch_yaw(rotation(r, p, y));
    EXPECT_NEAR(rpy[0], r, 1e-9);
    EXPECT_NEAR(rpy[1], p, 1e-9);
    EXPECT_NEAR(rpy[2], y, 1e-9);
  }
}

// t' = t + dt and R' = exp([w]x) R: the sensor displaced by dt and turned by w about itself, in the map
// frame.
TEST(PointToPlane, ApplyStepTurnsAboutTheSensorInTheMapFrame) {
  const Pose3 pose{2.0, -3.0, 5.5, 0.02, -0.3, 1.1};
  Vector6d step;
  step << 0.1, -0.2, 0.05, 0.01, -0.02, 0.03;
  const Pose3 moved = apply_step(pose, step);
  const Eigen::Vector3d w = step.tail<3>();
  const Eigen::Matrix3d expected = Eigen::AngleAxisd(w.norm(), w.normalized()) * rotation(0.02, -0.3, 1.1);
  EXPECT_LT((moved.to_isometry().linear() - expected).norm(), 1e-12);
  EXPECT_NEAR(moved.x, 2.1, 1e-15);
  EXPECT_NEAR(moved.y, -3.2, 1e-15);
  EXPECT_NEAR(moved.z, 5.55, 1e-15);
  // A point of the sensor frame: where it lands moves by dt plus the turn about the sensor.
  const Eigen::Vector3d p(10.0, 2.0, -1.0);
  const Eigen::Vector3d a = pose.to_isometry() * p;
  const Eigen::Vector3d t(pose.x, pose.y, pose.z);
  const Eigen::Vector3d landed = Eigen::AngleAxisd(w.norm(), w.normalized()) * (a - t) + t + step.head<3>();
  EXPECT_LT((moved.to_isometry() * p - landed).norm(), 1e-12);
  // No step: the same pose.
  EXPECT_LT((parameters(apply_step(pose, Vector6d::Zero())) - parameters(pose)).norm(), 1e-15);
}

TEST(PointToPlane, ParameterJacobianIsTheDerivativeOfApplyStep) {
  for (const Pose3& pose : {Pose3{1.0, 2.0, 6.0, 0.0, 0.0, 0.0}, Pose3{-4.0, 7.0, 4.5, 0.03, -0.05, 2.4},
                            Pose3{0.0, 0.0, 8.0, -0.4, 0.6, -2.9}}) {
    const Matrix6d j = pose_parameter_jacobian(pose);
    constexpr double h = 1e-5;  // another step than the function's own
    for (int k = 0; k < 6; ++k) {
      Vector6d plus = Vector6d::Zero(), minus = Vector6d::Zero();
      plus[k] = h;
      minus[k] = -h;
      Vector6d d = parameters(apply_step(pose, plus)) - parameters(apply_step(pose, minus));
      for (int a = 3; a < 6; ++a)
        d[a] = wrap_angle(d[a]);
      const Vector6d numeric = d / (2.0 * h);
      EXPECT_LT((j.col(k) - numeric).norm(), 1e-6) << "column " << k << " at yaw " << pose.yaw;
    }
  }
}

// A street of planes (the road, two facades, a kerb's face, a pole's two faces, a sloped roof) seen from
// a true mount; the points' sensor coordinates put back through a mount slightly off. Gauss-Newton steps
// from there reach the true mount, and the information is the residuals' J^T J over sigma^2.
struct PlaneScene {
  std::vector<PlaneMatch> matches;
};

PlaneScene street_seen_from(const Pose3& truth, double noise_m, std::mt19937& rng) {
  struct Plane {
    Eigen::Vector3d point, normal, u, v;  // u, v: two directions in the plane
  };
  const auto plane = [](Eigen::Vector3d point, Eigen::Vector3d normal) {
    normal.normalize();
    const Eigen::Vector3d u = normal.unitOrthogonal();
    return Plane{point, normal, u, normal.cross(u)};
  };
  const std::vector<Plane> planes = {plane({0, 0, 0}, {0, 0, 1}),   plane({0, 12, 0}, {0, -1, 0}),
                                     plane({0, -9, 0}, {0, 1, 0}),  plane({0, -6, 0}, {0, 1, 0.02}),
                                     plane({15, 3, 0}, {-1, 0, 0}), plane({15, 3, 0}, {0, -1, 0}),
                                     plane({-20, 0, 6}, {1, 0, 1}), plane({30, -2, 0}, {-1, 0.3, 0})};
  const Eigen::Isometry3d map_from_sensor = truth.to_isometry();
  std::normal_distribution<double> noise(0.0, noise_m);
  std::uniform_real_distribution<double> spread(-6.0, 6.0);
  PlaneScene scene;
  for (const Plane& pl : planes) {
    for (int i = 0; i < 60; ++i) {
      const Eigen::Vector3d on = pl.point + spread(rng) * pl.u + spread(rng) * pl.v;
      const Eigen::Vector3d seen = on + noise(rng) * pl.normal;
      scene.matches.push_back({map_from_sensor.inverse() * seen, pl.point, pl.normal, 0.02});
    }
  }
  return scene;
}

TEST(PointToPlane, GaussNewtonReachesTheMountThePlanesWereSeenFrom) {
  std::mt19937 rng(5);
  const Pose3 truth{3.0, -2.0, 6.0, 0.01, -0.02, 0.7};
  const PlaneScene scene = street_seen_from(truth, 0.0, rng);
  Vector6d off;
  off << 0.15, -0.10, 0.05, deg_to_rad(0.5), deg_to_rad(-0.4), deg_to_rad(1.0);
  Pose3 pose = apply_step(truth, off);
  const double error_before = (parameters(pose) - parameters(truth)).norm();
  const PlaneFit first = fit_planes(scene.matches, pose, 3.0);
  EXPECT_EQ(first.matches, scene.matches.size());
  EXPECT_EQ(first.vertical_matches, 6U * 60U);  // the facades, the kerb, the pole's two faces, the far wall
  EXPECT_GT(first.rms_m, 0.01);                 // off by decimetres before the step
  pose = apply_step(pose, first.step);
  const double error_after_one = (parameters(pose) - parameters(truth)).norm();
  EXPECT_LT(error_after_one, 0.05 * error_before);  // nearly linear this close: one step does most
  for (int i = 0; i < 3; ++i)
    pose = apply_step(pose, fit_planes(scene.matches, pose, 3.0).step);
  EXPECT_LT((parameters(pose) - parameters(truth)).norm(), 1e-8);
}

TEST(PointToPlane, InformationIsTheResidualsJacobianOverTheirVariance) {
  std::mt19937 rng(9);
  const Pose3 truth{3.0, -2.0, 6.0, 0.01, -0.02, 0.7};
  const double sigma = 0.02;
  const PlaneScene scene = street_seen_from(truth, sigma, rng);
  const PlaneFit fit = fit_planes(scene.matches, truth, 1e9);  // no point down-weighted
  // J^T J / sigma^2 from the residual's definition, by central differences of r = n . (T p - q).
  Matrix6d jtj = Matrix6d::Zero();
  double squares = 0.0;
  for (const PlaneMatch& m : scene.matches) {
    Eigen::Matrix<double, 1, 6> row;
    for (int k = 0; k < 6; ++k) {
      Vector6d plus = Vector6d::Zero(), minus = Vector6d::Zero();
      plus[k] = 1e-6;
      minus[k] = -1e-6;
      const double rp = m.normal.dot(apply_step(truth, plus).to_isometry() * m.sensor_point - m.plane_point);
      const double rm = m.normal.dot(apply_step(truth, minus).to_isometry() * m.sensor_point - m.plane_point);
      row[k] = (rp - rm) / 2e-6;
    }
    jtj += row.transpose() * row / (sigma * sigma);
    const double r = m.normal.dot(truth.to_isometry() * m.sensor_point - m.plane_point);
    squares += r * r / (sigma * sigma);
  }
  const double scale = std::sqrt(squares / static_cast<double>(scene.matches.size() - 6));
  EXPECT_NEAR(fit.scale, scale, 1e-9);
  EXPECT_NEAR(fit.scale, 1.0, 0.15);  // the noise as stated
  EXPECT_LT((fit.information - jtj / (scale * scale)).norm(), 1e-4 * jtj.norm());
  // At the truth the step is within the noise's reach: its covariance's few sigmas.
  const Matrix6d covariance = fit.information.inverse();
  for (int k = 0; k < 6; ++k)
    EXPECT_LT(std::abs(fit.step[k]), 4.0 * std::sqrt(covariance(k, k))) << "parameter " << k;
}

// Too few matches to fit six parameters: no step, no information, nothing divided by zero.
TEST(PointToPlane, SixMatchesOrFewerTakeNoStep) {
  std::mt19937 rng(2);
  PlaneScene scene = street_seen_from(Pose3{}, 0.02, rng);
  scene.matches.resize(6);
  const PlaneFit fit = fit_planes(scene.matches, Pose3{0.1, 0, 0, 0, 0, 0}, 3.0);
  EXPECT_EQ(fit.matches, 6U);
  EXPECT_EQ(fit.step, Vector6d::Zero());
  EXPECT_EQ(fit.information, Matrix6d::Zero());
  EXPECT_TRUE(fit.information.allFinite());
}

}  // namespace
}  // namespace rsu::calibration
