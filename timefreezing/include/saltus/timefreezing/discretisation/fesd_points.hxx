// FesdMpcc: the reading of a point x as the discrete solution (fesd.hpp, FesdPoint).
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hpp>
#include <saltus/timefreezing/discretisation/fesd_stage_rows.hxx>

#include <vector>

namespace saltus::timefreezing {

template <Scene S, class Ocp>
auto FesdMpcc<S, Ocp>::points(const Eigen::Ref<const Eigen::VectorXd>& x) const -> std::vector<Point> {
  std::vector<Point> out;
  Point p0;
  p0.y = y0_;
  p0.alpha.setConstant(0.5);
  p0.ode_weight = 1.0;
  p0.u = applied_input(x, 0, y0_[System::clock_index]);
  out.push_back(p0);
  double tau = 0.0;
  for (int k = 0; k < options_.grid.control_intervals; ++k)
    for (int j = 0; j < options_.grid.finite_elements; ++j) {
      const double h = x[length_index(k, j)];
      for (int r = 0; r < options_.grid.stages; ++r) {
        Point p;
        p.interval = k;
        p.element = j;
        p.stage = r;
        p.tau = tau + tableau_.c[r] * h;
        p.y = x.template segment<ny>(state_index(k, j, r));
        p.alpha = x.template segment<nsw>(alpha_index(k, j, r));
        p.ode_weight = System::template ode_weight<double>(p.alpha);
        p.u = applied_input(x, k, p.y[System::clock_index]);
        out.push_back(p);
      }
      tau += h;
    }
  return out;
}

}  // namespace saltus::timefreezing
