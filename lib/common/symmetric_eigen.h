// SPDX-License-Identifier: Apache-2.0
// The eigen-decomposition of a small symmetric matrix (covariances, information matrices), compiled once.
// Eigen's SelfAdjointEigenSolver is a template that every file using it compiled again: one 2x2 or 6x6
// instantiation cost 15-21 s of compile time in the sanitizer builds, in over a dozen files. This class
// keeps the solver's interface (eigenvalues ascending, eigenvectors as columns, info()) and its results
// (it calls Eigen's compute()); its members are defined in symmetric_eigen.cpp for N = 2, 3 and 6 only.
#pragma once

#include <Eigen/Core>

namespace rsu {

template <int N>
class SymmetricEigen {
 public:
  using Matrix = Eigen::Matrix<double, N, N>;
  using Vector = Eigen::Matrix<double, N, 1>;

  // Only the lower triangle of `m` is read, as Eigen's solver does.
  explicit SymmetricEigen(const Matrix& m);

  const Vector& eigenvalues() const { return values_; }
  const Matrix& eigenvectors() const { return vectors_; }
  Eigen::ComputationInfo info() const { return info_; }

 private:
  Vector values_;
  Matrix vectors_;
  Eigen::ComputationInfo info_;
};

using SymmetricEigen2 = SymmetricEigen<2>;
using SymmetricEigen3 = SymmetricEigen<3>;
using SymmetricEigen6 = SymmetricEigen<6>;

}  // namespace rsu
