// SPDX-License-Identifier: Apache-2.0
#include "tracking/assignment.h"

#include <algorithm>
#include <limits>

namespace rsu::tracking {
namespace {

// Rows are inserted one at a time. For each, a Dijkstra-like search over reduced costs
// cost(r, c) - row_potential[r] - col_potential[c] (kept >= 0 on every pair, 0 on matched pairs) finds
// the cheapest augmenting path from the new row to a free column; the potentials are shifted so the
// path becomes tight, and the matching is flipped along it. Requires rows <= cols.
std::vector<int> assign_rows_to_columns(const Eigen::MatrixXd& cost) {
  const int rows = static_cast<int>(cost.rows());
  const int cols = static_cast<int>(cost.cols());
  const double inf = std::numeric_limits<double>::infinity();
  const int start = cols;  // a virtual column that holds the row being inserted

  std::vector<double> row_potential(static_cast<std::size_t>(rows), 0.0);
  std::vector<double> col_potential(static_cast<std::size_t>(cols) + 1, 0.0);
  std::vector<int> row_of_col(static_cast<std::size_t>(cols) + 1, -1);
  std::vector<double> path_cost(static_cast<std::size_t>(cols));
  std::vector<int> came_from(static_cast<std::size_t>(cols));
  std::vector<char> done(static_cast<std::size_t>(cols) + 1);

  const auto at = [](auto& v, int i) -> auto& {
    return v[static_cast<std::size_t>(i)];
  };

  for (int r = 0; r < rows; ++r) {
    at(row_of_col, start) = r;
    std::fill(path_cost.begin(), path_cost.end(), inf);
    std::fill(came_from.begin(), came_from.end(), start);
    std::fill(done.begin(), done.end(), 0);
    int col = start;
    while (true) {
      at(done, col) = 1;
      const int row = at(row_of_col, col);
      double step = inf;
      int next = -1;
      for (int c = 0; c < cols; ++c) {
        if (at(done, c)) {
          continue;
        }
        const double reduced = cost(row, c) - at(row_potential, row) - at(col_potential, c);
        if (reduced < at(path_cost, c)) {
          at(path_cost, c) = reduced;
          at(came_from, c) = col;
        }
        if (at(path_cost, c) < step) {
          step = at(path_cost, c);
          next = c;
        }
      }
      if (next < 0) {
        break;  // cannot happen with rows <= cols; kept so bad input cannot loop
      }
      for (int c = 0; c <= cols; ++c) {
        if (at(done, c)) {
          at(row_potential, at(row_of_col, c)) += step;
          at(col_potential, c) -= step;
        } else {
          at(path_cost, c) -= step;
        }
      }
      col = next;
      if (at(row_of_col, col) < 0) {
        break;  // reached a free column
      }
    }
    // Flip the matching along the path back to the virtual start column.
    while (col != start) {
      const int previous = at(came_from, col);
      at(row_of_col, col) = at(row_of_col, previous);
      col = previous;
    }
  }

  std::vector<int> row_to_col(static_cast<std::size_t>(rows), -1);
  for (int c = 0; c < cols; ++c) {
    if (at(row_of_col, c) >= 0) {
      at(row_to_col, at(row_of_col, c)) = c;
    }
  }
  return row_to_col;
}

}  // namespace

std::optional<Assignment> solve_assignment(const Eigen::MatrixXd& cost) {
  if (!cost.allFinite()) {
    return std::nullopt;
  }
  Assignment out;
  out.row_to_col.assign(static_cast<std::size_t>(cost.rows()), -1);
  if (cost.rows() == 0 || cost.cols() == 0) {
    return out;
  }
  if (cost.rows() <= cost.cols()) {
    out.row_to_col = assign_rows_to_columns(cost);
  } else {
    const std::vector<int> col_to_row = assign_rows_to_columns(cost.transpose());
    for (std::size_t c = 0; c < col_to_row.size(); ++c) {
      out.row_to_col[static_cast<std::size_t>(col_to_row[c])] = static_cast<int>(c);
    }
  }
  for (std::size_t r = 0; r < out.row_to_col.size(); ++r) {
    if (out.row_to_col[r] >= 0) {
      out.total_cost += cost(static_cast<Eigen::Index>(r), out.row_to_col[r]);
    }
  }
  return out;
}

}  // namespace rsu::tracking
