// Definitions of constraints.hpp (see there for the math).
#pragma once

#include <saltus/hybrid/dynamics/constraints.hpp>

#include <limits>

namespace saltus {

template <Scene S>
void ConstraintProjection<S>::assemble(const S& scene, const Mode<nc>& mode, bool velocity_rows) {
  std::array<ContactRows, nc> layout{};
  for (int i = 0; i < nc; ++i) {
    if (!mode[i].closed())
      layout[i] = ContactRows::None;
    else if (velocity_rows && mode[i].mode == ContactMode::Stick)
      layout[i] = ContactRows::Stick;  // the normal row and the tangent rows
    else
      layout[i] = ContactRows::Normal;
  }
  assembly_.assemble(scene, kin_, layout, no_slip_);
  assembly_.form(kin_);
}

template <Scene S>
void ConstraintProjection<S>::values(const S& scene, const Mode<nc>& mode, const State& x, Values& c_q, Values& c_v) {
  evaluate_kinematics(scene, VecT<double, nq>(x.template head<nq>()), VecT<double, nq>(x.template tail<nq>()), kin_);
  int m = 0;
  for (int i = 0; i < nc; ++i) m += mode[i].closed();
  c_q.resize(m);
  m = 0;
  for (int i = 0; i < nc; ++i)
    if (mode[i].closed()) c_q[m++] = kin_.contacts[i].gap;
  assemble(scene, mode, true);
  const int r = assembly_.rows;
  c_v.resize(r);
  if (r > 0) c_v.noalias() = assembly_.J.topRows(r) * x.template tail<nq>();
}

template <Scene S>
void ConstraintProjection<S>::kinetic_step(const Values& b, VecT<double, nq>& d) {
  d.setZero();
  const int m = assembly_.rows;
  if (m == 0) return;
  solver_.matrix(m) = assembly_.D.topLeftCorner(m, m);
  solver_.factorize();
  multiplier_ = b.head(m);
  solver_.solve_in_place(multiplier_);
  d.noalias() = assembly_.MinvF.leftCols(m) * multiplier_;
}

template <Scene S>
void ConstraintProjection<S>::project(const S& scene, const Mode<nc>& mode, State& x, const Values* c_q_target,
                                      const Values* c_v_target, State* error) {
  VecT<double, nq> q = x.template head<nq>(), v = x.template tail<nq>(), d;
  int closed = 0;
  for (int i = 0; i < nc; ++i) closed += mode[i].closed();
  if (closed == 0) return;
  SALTUS_REQUIRE(!c_q_target || c_q_target->size() == closed, "constraint projection: ", c_q_target->size(),
                 " configuration targets for ", closed, " closed contacts");
  const double scale = 1.0 + q.cwiseAbs().maxCoeff();
  // Configuration: Gauss-Newton on c_q(q) = c_q*.
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    evaluate_kinematics(scene, q, v, kin_);
    assemble(scene, mode, false);
    residual_.resize(closed);
    int k = 0;
    for (int i = 0; i < nc; ++i)
      if (mode[i].closed()) residual_[k++] = kin_.contacts[i].gap;
    if (c_q_target) residual_ -= *c_q_target;
    kinetic_step(residual_, d);
    q -= d;
    if (d.cwiseAbs().maxCoeff() <= 4 * std::numeric_limits<double>::epsilon() * scale) break;
  }
  evaluate_kinematics(scene, q, v, kin_);
  if (error) {  // its configuration part, with the last G
    assemble(scene, mode, false);
    residual_.noalias() = assembly_.J.topRows(closed) * error->template head<nq>();
    kinetic_step(residual_, d);
    error->template head<nq>() -= d;
  }
  // Velocity: exact kinetic-metric projection onto J v = c_v* at the new configuration.
  assemble(scene, mode, true);
  const int r = assembly_.rows;
  SALTUS_REQUIRE(!c_v_target || c_v_target->size() == r, "constraint projection: ", c_v_target->size(),
                 " velocity targets for ", r, " velocity constraints");
  residual_.resize(r);
  residual_.noalias() = assembly_.J.topRows(r) * v;
  if (c_v_target) residual_ -= *c_v_target;
  kinetic_step(residual_, d);
  v -= d;
  if (error) {
    residual_.noalias() = assembly_.J.topRows(r) * error->template tail<nq>();
    kinetic_step(residual_, d);
    error->template tail<nq>() -= d;
  }
  x.template head<nq>() = q;
  x.template tail<nq>() = v;
}

}  // namespace saltus
