// FesdMpcc: the constraint values and their sparse Jacobian, one pass over the rows (fesd.hpp).
//
// DERIVATIVES: every nonlinear block is a templated function of a small local vector (the stage
// dynamics: z = (q, v, t, u, alpha) and (q, K_v); the switching functions: (q, v); the path rows:
// (Y, u); the terminal rows and cost: (x, t)); its Jacobian is forward AD (saltus::ad::Dual), its
// Lagrangian Hessian forward-over-forward AD (fesd_hessian.hxx), assembled into the global sparse
// structure built once at construction. Bilinear and linear terms are written out.
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hpp>
#include <saltus/timefreezing/discretisation/fesd_stage_rows.hxx>

namespace saltus::timefreezing {

// One pass: per stage point its four row blocks, per control interval its element-length sum and
// clock rows, then the terminal rows (the row order of build_rows).
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::jacobian_pass(const Eigen::Ref<const Eigen::VectorXd>& x, detail::JacobianSink& sink) const {
  for (int k = 0; k < options_.grid.control_intervals; ++k) {
    for (int j = 0; j < options_.grid.finite_elements; ++j)
      for (int r = 0; r < options_.grid.stages; ++r) {
        dynamics_rows(x, k, j, r, sink);
        collocation_rows(x, k, j, r, sink);
        switching_rows(x, k, j, r, sink);
        path_rows(x, k, j, r, sink);
      }
    interval_rows(x, k, sink);
  }
  terminal_rows(x, sink);
}

// sum_j h_kj (= T~ / N by its bounds) and the clock t at the interval's end.
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::interval_rows(const Eigen::Ref<const Eigen::VectorXd>& x, int k, detail::JacobianSink& sink) const {
  const int ir = interval_row_[static_cast<std::size_t>(k)];
  double sum_h = 0.0;
  for (int j = 0; j < options_.grid.finite_elements; ++j) {
    sum_h += x[length_index(k, j)];
    sink.put(ir, length_index(k, j), 1.0);
  }
  sink.value(ir, sum_h);
  if (has_clock_row(k)) {
    const int yk = state_index(k, options_.grid.finite_elements - 1, options_.grid.stages - 1) + System::clock_index;
    sink.value(ir + 1, x[yk]);
    sink.put(ir + 1, yk, 1.0);
  }
}

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::terminal_rows(const Eigen::Ref<const Eigen::VectorXd>& x, detail::JacobianSink& sink) const {
  if constexpr (nt > 0) {
    Eigen::Matrix<double, ntw, 1> tw;
    for (int a = 0; a < ntw; ++a) tw[a] = x[terminal_global(a)];
    const VecT<detail::Ad1<ntw>, nt> tf = terminal_function<detail::Ad1<ntw>>(detail::seed_first<ntw>(tw));
    for (int i = 0; i < nt; ++i) {
      sink.value(terminal_row_ + i, tf[i].value());
      for (int b = 0; b < ntw; ++b) sink.put(terminal_row_ + i, terminal_global(b), tf[i].derivatives()[b]);
    }
  } else {
    (void)x, (void)sink;
  }
}

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::constraints(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const {
  detail::JacobianSink sink;
  sink.g = &g;
  jacobian_pass(x, sink);
}
template <Scene S, class Ocp>
const std::vector<SparseEntry>& FesdMpcc<S, Ocp>::jacobian_structure() const {
  return jacobian_structure_;
}
template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::jacobian_values(const Eigen::Ref<const Eigen::VectorXd>& x,
                                       Eigen::Ref<Eigen::VectorXd> values) const {
  detail::JacobianSink sink;
  sink.values = &values;
  jacobian_pass(x, sink);
}

}  // namespace saltus::timefreezing
