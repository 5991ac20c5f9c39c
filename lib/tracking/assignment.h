// SPDX-License-Identifier: Apache-2.0
// Minimum-cost assignment (the linear assignment problem), solved exactly with the Hungarian method in
// its shortest-augmenting-path form (Kuhn 1955, Munkres 1957; the O(n^2 m) variant with row and column
// potentials also used by Jonker and Volgenant 1987).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

namespace rsu::tracking {

struct Assignment {
  // row_to_col[r] is the column given to row r, or -1 when there are more rows than columns and r got
  // none. Every column is used at most once.
  std::vector<int> row_to_col;
  double total_cost = 0.0;
};

// Assigns every row to a distinct column (or every column to a distinct row, whichever is fewer) so
// that the summed cost is minimal. Empty when a cost is NaN or infinite: forbid a pairing with a large
// finite cost instead.
std::optional<Assignment> solve_assignment(const Eigen::MatrixXd& cost);

}  // namespace rsu::tracking
