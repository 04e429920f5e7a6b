// Definitions of mode_selection.hpp (see there for the math).
#pragma once

#include <saltus/hybrid/dynamics/mode_selection.hpp>

namespace saltus {

template <Scene S>
auto ModeSelector<S>::select(const VecT<double, nx>& x, const VecT<double, nu>& u,
                             const std::array<bool, nc>& candidates, const std::array<bool, nc>& rest) -> Mode<nc> {
  const VecT<double, nq> q = x.template head<nq>(), v = x.template tail<nq>();
  evaluate_kinematics(scene_, q, v, kin_);
  VecT<double, nq> free_force = -kin_.h;
  if constexpr (nu > 0) free_force += kin_.S_u * u;
  const VecT<double, nq> a_free = kin_.llt.solve(free_force);
  const double v_tol = options_.velocity_tolerance * std::max(1.0, v.cwiseAbs().maxCoeff());

  problem_.reset();
  std::array<int, nc> index{};
  std::array<Eigen::Vector2d, nc> slip_dir{};
  std::array<ContactRows, nc> layout{};
  bool any_spatial = false;
  for (int i = 0; i < nc; ++i) {
    index[i] = -1;
    layout[i] = ContactRows::None;
    if (!candidates[i]) continue;
    const auto& c = kin_.contacts[i];
    const int nt = c.tangents;
    const double speed = c.zeta_t.head(nt).norm();
    slip_dir[i].setZero();
    if (nt > 0 && !rest[i] && speed > v_tol) {
      slip_dir[i].head(nt) = c.zeta_t.head(nt) / speed;
      index[i] = problem_.add_contact(0, 0.0);  // friction prescribed along -zeta_t
      layout[i] = ContactRows::Slip;
    } else {
      index[i] = problem_.add_contact(nt, scene_.contact(i).mu);
      layout[i] = ContactRows::Stick;
      any_spatial = any_spatial || nt == 2;
    }
  }
  problem_.resize();
  // The assembly stacks the contacts in the problem's row order: normal, then its tangents.
  assembly_.assemble(scene_, kin_, layout, slip_dir);
  const int m = problem_.rows();
  SALTUS_INVARIANT(assembly_.rows == m, "the Delassus assembly has the contact problem's rows");
  Mode<nc> mode;
  if (m == 0) return mode;
  assembly_.form(kin_);
  problem_.A = assembly_.D;
  problem_.b.noalias() = assembly_.J.topRows(m) * a_free;
  for (int i = 0; i < nc; ++i) {
    if (index[i] < 0) continue;
    const auto& c = kin_.contacts[i];
    const int r = problem_.row[index[i]];
    problem_.b[r] += c.kappa_n;
    for (int k = 0; k < problem_.tangents[index[i]]; ++k) problem_.b[r + 1 + k] += c.kappa_t[k];
  }

  solution_.lambda.resize(m);
  solution_.y.resize(m);
  bool solved = false;
  if (!any_spatial) {
    lemke_.solve(problem_, solution_);
    solved = solution_.residual <= options_.residual_tolerance;
  }
  if (!solved) {
    coulomb_.solve(problem_, solution_);
    solved = solution_.residual <= options_.residual_tolerance;
  }
  if (!solved) {
    throw ContactProblemFailure(detail::concat(
        "no consistent contact mode at the acceleration level (Painleve's paradox or a wrong contact set): "
        "natural-map residual ",
        solution_.residual, " at x = [", x.transpose(), "]"));
  }

  const double force_scale = std::max(solution_.lambda.head(m).cwiseAbs().maxCoeff(),
                                      contact_problem_scale(problem_) * problem_.b.head(m).cwiseAbs().maxCoeff());
  const double acc_scale =
      std::max(problem_.b.head(m).cwiseAbs().maxCoeff(), solution_.y.head(m).cwiseAbs().maxCoeff());
  for (int i = 0; i < nc; ++i) {
    if (index[i] < 0) continue;
    const int r = problem_.row[index[i]];
    const int nt = problem_.tangents[index[i]];
    const double ln = solution_.lambda[r], yn = solution_.y[r];
    if (ln <= options_.force_tolerance * force_scale && yn > options_.acceleration_tolerance * acc_scale) {
      mode[i] = ContactState::open();
      continue;
    }
    const int tangents = kin_.contacts[i].tangents;
    if (tangents == 0) {
      mode[i] = ContactState::slip(Eigen::Vector2d::Zero());
    } else if (nt == 0) {  // already slipping
      mode[i] =
          tangents == 1 ? ContactState::slip_planar(slip_dir[i][0] > 0 ? 1 : -1) : ContactState::slip(slip_dir[i]);
    } else {
      Eigen::Vector2d yt = Eigen::Vector2d::Zero();
      for (int k = 0; k < nt; ++k) yt[k] = solution_.y[r + 1 + k];
      if (yt.norm() <= options_.acceleration_tolerance * acc_scale) {
        mode[i] = ContactState::stick();
      } else {
        const Eigen::Vector2d d = yt / yt.norm();
        mode[i] = nt == 1 ? ContactState::slip_planar(d[0] > 0 ? 1 : -1) : ContactState::slip(d);
      }
    }
  }
  return mode;
}

}  // namespace saltus
