// The fitted order of a first-order prediction's remainder r(eps), for the benchmarks.
// The remainder of a right first-order term falls like eps^2 until it meets the integration floor
// (the noise of the re-simulations, ~1e-12 on the hopper, ~1e-14 on the plank-box at tolerances
// 1e-13), where it stops falling. A point near the floor drags a fitted slope down (5.1e-7, 5.1e-9,
// 5.5e-11, 2.7e-12, 2.4e-12 on the hopper's second impact: exact eps^2 over the first three, 1.78
// when the fourth is fitted too). So the slope is fitted on the points at least `factor` times the
// smallest remainder measured (an upper bound of the floor): each such point carries at most
// 1/factor of floor. A wrong first-order term still shows: its remainder falls like eps (slope 1)
// far above the floor.
#pragma once

#include <saltus/sensitivity/prediction_check.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace saltus::bench {

struct RemainderSlope {
  double slope = NAN;  ///< NaN when fewer than two points are above the floor, or `exact`
  int points = 0;      ///< the points fitted
  bool exact = false;  ///< every remainder at round-off (<= 1e-13): the motion is linear in eps
};

inline RemainderSlope slope_above_floor(const std::vector<double>& eps, const std::vector<double>& r,
                                        double factor = 30.0) {
  RemainderSlope s;
  if (r.empty()) return s;
  const double largest = *std::max_element(r.begin(), r.end());
  if (largest <= 1e-13) {
    s.exact = true;
    return s;
  }
  const double floor = *std::min_element(r.begin(), r.end());
  std::vector<double> e, y;
  for (std::size_t k = 0; k < r.size(); ++k)
    if (r[k] >= factor * floor) {
      e.push_back(eps[k]);
      y.push_back(r[k]);
    }
  s.points = static_cast<int>(e.size());
  if (e.size() >= 2) s.slope = fitted_log_slope(e, y);
  return s;
}

}  // namespace saltus::bench
