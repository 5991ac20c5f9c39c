// SPDX-License-Identifier: Apache-2.0
#include "fusion/measurement_model.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "common/angles.h"
#include "common/symmetric_eigen.h"
#include "fusion/covariance_floor.h"

namespace rsu::fusion {
namespace {

TEST(MeasurementModel, YawResidualBranches) {
  // NDT: modulo 2 pi.
  EXPECT_NEAR(yaw_residual(0.2, 0.1, MeasurementSource::kNdt), 0.1, 1e-12);
  EXPECT_NEAR(yaw_residual(-kPi + 0.05, kPi - 0.05, MeasurementSource::kNdt), 0.1, 1e-12);
  EXPECT_NEAR(yaw_residual(0.1 + kPi, 0.1, MeasurementSource::kNdt), kPi, 1e-12);
  // RSU: modulo pi, so a box pointing backwards is no residual at all.
  EXPECT_NEAR(yaw_residual(0.1 + kPi, 0.1, MeasurementSource::kRsu), 0.0, 1e-12);
  EXPECT_NEAR(yaw_residual(0.3 - kPi, 0.1, MeasurementSource::kRsu), 0.2, 1e-12);
  EXPECT_NEAR(std::abs(yaw_residual(0.1 + kPi / 2.0, 0.1, MeasurementSource::kRsu)), kPi / 2.0, 1e-12);
  for (double m = -3.0; m <= 3.0; m += 0.37) {
    const double r = yaw_residual(m, 0.4, MeasurementSource::kRsu);
    EXPECT_LE(std::abs(r), kPi / 2.0 + 1e-12);
    // m and 0.4 + r are the same line direction.
    EXPECT_NEAR(std::abs(std::sin(m - (0.4 + r))), 0.0, 1e-12);
  }
}

TEST(MeasurementModel, BoxCentreFromReferencePoint) {
  // Facing north, rear axle 1.35 m behind the centre: the centre is 1.35 m north of the axle.
  const Eigen::Vector2d c = box_centre_from_reference(10.0, 20.0, kPi / 2.0, {-1.35, 0.0});
  EXPECT_NEAR(c.x(), 10.0, 1e-12);
  EXPECT_NEAR(c.y(), 21.35, 1e-12);
  // A reference point on the left side (y = +0.9): the centre is 0.9 m to its right, i.e. east.
  const Eigen::Vector2d d = box_centre_from_reference(0.0, 0.0, kPi / 2.0, {0.0, 0.9});
  EXPECT_NEAR(d.x(), 0.9, 1e-12);
  EXPECT_NEAR(d.y(), 0.0, 1e-12);
}

TEST(MeasurementModel, RsuJacobianMatchesFiniteDifferences) {
  StateVector s;
  s << 3.0, 4.0, 0.7, 5.0, 0.1;
  PoseMeasurement m;
  m.source = MeasurementSource::kRsu;
  m.pose = {0.0, 0.0, 0.0};
  const Eigen::Vector2d offset(-1.35, 0.4);
  const PoseInnovation at = pose_innovation(s, m, offset);
  const double h = 1e-6;
  StateVector plus = s;
  StateVector minus = s;
  plus(kYaw) += h;
  minus(kYaw) -= h;
  // residual = z - h(x), so d(residual)/dx = -H.
  const Eigen::Vector3d numeric =
      -(pose_innovation(plus, m, offset).residual - pose_innovation(minus, m, offset).residual) / (2.0 * h);
  EXPECT_NEAR(at.jacobian(0, kYaw), numeric.x(), 1e-6);
  EXPECT_NEAR(at.jacobian(1, kYaw), numeric.y(), 1e-6);
  EXPECT_NEAR(at.jacobian(2, kYaw), 1.0, 1e-12);
}

TEST(MeasurementModel, WellFormedChecks) {
  PoseMeasurement m;
  m.covariance = Eigen::Vector3d(0.04, 0.04, 0.001).asDiagonal();
  EXPECT_TRUE(is_well_formed(m));
  m.covariance(2, 2) = 0.0;
  EXPECT_FALSE(is_well_formed(m));
  m.covariance(2, 2) = 0.001;
  m.pose.yaw = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(is_well_formed(m));
}

// The eigen-decomposition compiled once (common/symmetric_eigen.h) against matrices built from known
// eigenvalues and an orthonormal basis (Gram-Schmidt of random vectors, done here).
template <int N>
void expect_decomposes_known_matrices() {
  std::mt19937 rng(7 + N);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::Matrix<double, N, N> q;
    for (int c = 0; c < N; ++c) {
      Eigen::Matrix<double, N, 1> v;
      for (int r = 0; r < N; ++r)
        v[r] = u(rng);
      for (int k = 0; k < c; ++k)
        v -= v.dot(q.col(k)) * q.col(k);
      q.col(c) = v.normalized();
    }
    std::vector<double> lambda;
    for (int k = 0; k < N; ++k)
      lambda.push_back(std::pow(10.0, 3.0 * u(rng)));  // 1e-3 .. 1e3
    Eigen::Matrix<double, N, 1> l;
    for (int k = 0; k < N; ++k)
      l[k] = lambda[static_cast<std::size_t>(k)];
    const Eigen::Matrix<double, N, N> m = q * l.asDiagonal() * q.transpose();
    std::sort(lambda.begin(), lambda.end());
    const SymmetricEigen<N> eig(m);
    ASSERT_EQ(eig.info(), Eigen::Success);
    for (int k = 0; k < N; ++k)
      EXPECT_NEAR(eig.eigenvalues()[k], lambda[static_cast<std::size_t>(k)], 1e-9 * lambda.back());
    const Eigen::Matrix<double, N, N> v = eig.eigenvectors();
    EXPECT_LT((v.transpose() * v - Eigen::Matrix<double, N, N>::Identity()).norm(), 1e-12);
    EXPECT_LT((v * eig.eigenvalues().asDiagonal() * v.transpose() - m).norm(), 1e-9 * lambda.back());
  }
}

TEST(SymmetricEigen, DecomposesMatricesOfKnownEigenvalues) {
  expect_decomposes_known_matrices<2>();
  expect_decomposes_known_matrices<3>();
  expect_decomposes_known_matrices<6>();
}

TEST(CovarianceFloor, RaisesOnlyTheAxisBelowTheFloor) {
  // 0.5 m along 30 deg, 0.01 m across it: the floor of 0.05 m raises the across axis only.
  const double a = deg_to_rad(30.0);
  const Eigen::Vector2d along(std::cos(a), std::sin(a));
  const Eigen::Vector2d across(-std::sin(a), std::cos(a));
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  c.topLeftCorner<2, 2>() = 0.25 * along * along.transpose() + 1e-4 * across * across.transpose();
  c(2, 2) = 1.0;
  EXPECT_TRUE(raise_to_floor(c, 0.05, 0.01));
  EXPECT_NEAR(along.dot(c.topLeftCorner<2, 2>() * along), 0.25, 1e-12);
  EXPECT_NEAR(across.dot(c.topLeftCorner<2, 2>() * across), 0.0025, 1e-12);
  EXPECT_NEAR(c(2, 2), 1.0, 1e-15);
  EXPECT_FALSE(raise_to_floor(c, 0.05, 0.01));
}

}  // namespace
}  // namespace rsu::fusion
