// SPDX-License-Identifier: Apache-2.0
#include "tracking/assignment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <set>
#include <vector>

#include "common/random.h"

namespace rsu::tracking {
namespace {

// Minimum total over every injective assignment of the smaller side, by enumerating permutations.
double brute_force_minimum(const Eigen::MatrixXd& cost) {
  const bool transpose = cost.rows() > cost.cols();
  const Eigen::MatrixXd c = transpose ? Eigen::MatrixXd(cost.transpose()) : cost;
  std::vector<int> cols(static_cast<std::size_t>(c.cols()));
  std::iota(cols.begin(), cols.end(), 0);
  double best = std::numeric_limits<double>::infinity();
  do {
    double total = 0.0;
    for (Eigen::Index r = 0; r < c.rows(); ++r) {
      total += c(r, cols[static_cast<std::size_t>(r)]);
    }
    best = std::min(best, total);
  } while (std::next_permutation(cols.begin(), cols.end()));
  return best;
}

Eigen::MatrixXd random_matrix(int rows, int cols, std::uint64_t seed, bool integer) {
  Eigen::MatrixXd m(rows, cols);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const double u = uniform_open01(mix64(seed * 1'000'003ULL + static_cast<std::uint64_t>(r * 17 + c)));
      m(r, c) = integer ? std::floor(u * 5.0) : u * 100.0 - 20.0;  // integers: many ties
    }
  }
  return m;
}

TEST(Assignment, MatchesBruteForceOnRandomMatrices) {
  int checked = 0;
  for (std::uint64_t seed = 1; seed <= 400; ++seed) {
    const int rows = 1 + static_cast<int>(mix64(seed) % 7);
    const int cols = 1 + static_cast<int>(mix64(seed + 99) % 7);
    const Eigen::MatrixXd cost = random_matrix(rows, cols, seed, seed % 3 == 0);
    const auto result = solve_assignment(cost);
    ASSERT_TRUE(result.has_value());
    ASSERT_EQ(result->row_to_col.size(), static_cast<std::size_t>(rows));
    std::set<int> used;
    double total = 0.0;
    for (int r = 0; r < rows; ++r) {
      const int c = result->row_to_col[static_cast<std::size_t>(r)];
      if (c < 0) {
        continue;
      }
      ASSERT_LT(c, cols);
      EXPECT_TRUE(used.insert(c).second) << "column " << c << " used twice";
      total += cost(r, c);
    }
    EXPECT_EQ(used.size(), static_cast<std::size_t>(std::min(rows, cols)));
    const double best = brute_force_minimum(cost);
    EXPECT_NEAR(total, best, 1e-9) << rows << "x" << cols << " seed " << seed;
    EXPECT_NEAR(result->total_cost, best, 1e-9);
    ++checked;
  }
  EXPECT_EQ(checked, 400);
}

TEST(Assignment, GlobalOptimumIsNotGreedy) {
  // Greedy row by row takes (0,0)=1 and is left with (1,1)=100; the optimum is 2 + 3.
  Eigen::MatrixXd cost(2, 2);
  cost << 1, 2, 3, 100;
  const auto result = solve_assignment(cost);
  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(result->row_to_col, (std::vector<int>{1, 0}));
  EXPECT_DOUBLE_EQ(result->total_cost, 5.0);
}

TEST(Assignment, EmptyAndNonFiniteInputs) {
  EXPECT_TRUE(solve_assignment(Eigen::MatrixXd(0, 3)).has_value());
  const auto no_cols = solve_assignment(Eigen::MatrixXd(2, 0));
  ASSERT_TRUE(no_cols.has_value());
  EXPECT_EQ(no_cols->row_to_col, (std::vector<int>{-1, -1}));
  Eigen::MatrixXd bad = Eigen::MatrixXd::Ones(2, 2);
  bad(1, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(solve_assignment(bad).has_value());
  bad(1, 0) = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(solve_assignment(bad).has_value());
}

}  // namespace
}  // namespace rsu::tracking
