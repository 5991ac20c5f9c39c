// SPDX-License-Identifier: Apache-2.0
#include "common/symmetric_eigen.h"

#include <Eigen/Eigenvalues>

namespace rsu {

template <int N>
SymmetricEigen<N>::SymmetricEigen(const Matrix& m) {
  const Eigen::SelfAdjointEigenSolver<Matrix> solver(m);
  info_ = solver.info();
  values_ = solver.eigenvalues();
  vectors_ = solver.eigenvectors();
}

template class SymmetricEigen<2>;
template class SymmetricEigen<3>;
template class SymmetricEigen<6>;

}  // namespace rsu
