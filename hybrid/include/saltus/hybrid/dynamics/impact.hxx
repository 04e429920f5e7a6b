// Definitions of impact.hpp (see there for the math).
#pragma once

#include <saltus/hybrid/dynamics/impact.hpp>

namespace saltus {

template <Scene S>
ImpactSolver<S>::ImpactSolver(const S& scene, ImpactOptions options) : scene_(scene), options_(options) {
  validate_scene(scene);
  SALTUS_REQUIRE(options.gap_tolerance >= 0 && options.velocity_tolerance >= 0 && options.impulse_tolerance >= 0 &&
                    options.residual_tolerance > 0, "ImpactOptions: tolerances must be >= 0 (residual_tolerance > 0)");
  coulomb_.options = options.coulomb;
}

template <Scene S>
auto ImpactSolver<S>::solve(const VecT<double, nx>& x_minus) -> const ImpactResult<S>& {
  require_finite(x_minus, "pre-impact state x-");
  const int exponent = scale_velocity(x_minus);
  evaluate_kinematics(scene_, VecT<double, nq>(x_work_.template head<nq>()),
                      VecT<double, nq>(x_work_.template tail<nq>()), jump_.kin);
  std::array<bool, nc> in_problem{};
  for (int i = 0; i < nc; ++i) in_problem[i] = jump_.kin.contacts[i].gap <= options_.gap_tolerance;
  coefficients_ = impact_coefficients(scene_, jump_.kin, in_problem);
  solve_evaluated(x_work_, in_problem, x_minus);
  unscale_result(exponent, x_minus);
  return result_;
}

template <Scene S>
auto ImpactSolver<S>::solve(const VecT<double, nx>& x_minus, const std::array<bool, nc>& in_problem,
                            const std::array<bool, nc>& inelastic) -> const ImpactResult<S>& {
  require_finite(x_minus, "pre-impact state x-");
  const int exponent = scale_velocity(x_minus);
  evaluate_kinematics(scene_, VecT<double, nq>(x_work_.template head<nq>()),
                      VecT<double, nq>(x_work_.template tail<nq>()), jump_.kin);
  coefficients_ = impact_coefficients(scene_, jump_.kin, in_problem, inelastic);
  solve_evaluated(x_work_, in_problem, x_minus);
  unscale_result(exponent, x_minus);
  return result_;
}

// The impact problem is positively homogeneous of degree one in v- at fixed q: the law's
// coefficients depend on the signs of zeta_n^- only (impact_law.hpp), the mode on directions
// and ratios, the impulse and v+ scale with v-. Velocities far from unit scale are therefore
// solved at unit scale and scaled back, by a power of two (exact in binary floating point), so
// that squares and products in the solvers and residuals neither underflow nor overflow (found
// by fuzzing: pre-impact velocities of 1e-156 m/s give subnormal products and a Coulomb residual
// of 1e-9 made of round-off). Within [2^-32, 2^32] nothing is scaled and results are unchanged.
template <Scene S>
int ImpactSolver<S>::scale_velocity(const VecT<double, nx>& x_minus) {
  x_work_ = x_minus;
  const double v_max = x_minus.template tail<nq>().cwiseAbs().maxCoeff();
  if (!(v_max > 0.0) || (v_max >= 0x1p-32 && v_max <= 0x1p32)) return 0;
  const int exponent = std::ilogb(v_max);
  for (int k = nq; k < nx; ++k) x_work_[k] = std::ldexp(x_minus[k], -exponent);
  return exponent;
}

template <Scene S>
void ImpactSolver<S>::unscale_result(int exponent, const VecT<double, nx>& x_minus) {
  if (exponent == 0) return;
  auto& r = result_;
  r.x_plus.template head<nq>() = x_minus.template head<nq>();
  for (int k = nq; k < nx; ++k) r.x_plus[k] = std::ldexp(r.x_plus[k], exponent);
  for (int i = 0; i < nc; ++i) {
    r.impulse[i].normal = std::ldexp(r.impulse[i].normal, exponent);
    for (int k = 0; k < 2; ++k) {
      r.impulse[i].tangent[k] = std::ldexp(r.impulse[i].tangent[k], exponent);
      r.tangent_velocity_plus[i][k] = std::ldexp(r.tangent_velocity_plus[i][k], exponent);
    }
    r.normal_velocity_minus[i] = std::ldexp(r.normal_velocity_minus[i], exponent);
    r.normal_velocity_plus[i] = std::ldexp(r.normal_velocity_plus[i], exponent);
  }
  r.kinetic_energy_minus = std::ldexp(r.kinetic_energy_minus, 2 * exponent);
  r.kinetic_energy_plus = std::ldexp(r.kinetic_energy_plus, 2 * exponent);
  r.velocity_scale = std::ldexp(r.velocity_scale, exponent);
  r.impulse_scale = std::ldexp(r.impulse_scale, exponent);
}

template <Scene S>
void ImpactSolver<S>::solve_evaluated(const VecT<double, nx>& x_minus, const std::array<bool, nc>& in_problem,
                                      const VecT<double, nx>& x_reported) {
  auto& r = result_;
  const auto& kin = jump_.kin;
  const VecT<double, nq> v_minus = x_minus.template tail<nq>();
  r.in_problem = in_problem;
  r.coefficients = coefficients_;
  r.kinetic_energy_minus = kinetic_energy(kin.M, v_minus);

  // Contact problem y = W M^{-1} W^T Lambda + b.
  problem_.reset();
  std::array<int, nc> index{};
  bool any_spatial = false;
  for (int i = 0; i < nc; ++i) {
    index[i] = -1;
    if (!in_problem[i]) continue;
    const int nt = kin.contacts[i].tangents;
    any_spatial = any_spatial || nt == 2;
    index[i] = problem_.add_contact(nt, scene_.contact(i).mu);
  }
  problem_.resize();
  const int m = problem_.rows();
  velocity_scale_ = 0.0;
  // W stacks w_n^T and W_t^T of every contact in the problem, in the problem's row order.
  std::array<ContactRows, nc> layout{};
  for (int i = 0; i < nc; ++i) layout[i] = index[i] < 0 ? ContactRows::None : ContactRows::Stick;
  assembly_.assemble(scene_, kin, layout, no_slip_directions_);
  SALTUS_INVARIANT(assembly_.rows == m, "the Delassus assembly has the contact problem's rows");
  assembly_.form(kin);
  if (m > 0) problem_.A = assembly_.D;
  // Rank of the whole problem's Delassus matrix (every contact in the problem, normal and
  // tangential rows): deficient for redundant contacts, whose impulse split is then not unique.
  problem_rank_ = 0;
  if (m > 0) {
    problem_delassus_.matrix(m) = assembly_.D.topLeftCorner(m, m);
    problem_delassus_.factorize();
    problem_rank_ = problem_delassus_.rank();
  }
  const auto W = assembly_.J.topRows(m);
  const auto MinvWt = assembly_.MinvF.leftCols(m);
  problem_.b.noalias() = W * v_minus;
  for (int k = 0; k < m; ++k) velocity_scale_ = std::max(velocity_scale_, std::abs(problem_.b[k]));
  // The impact law's velocities (impact_law.hpp): y = xi = W v+ + (e_n min(zeta_n-, 0), e_t zeta_t-).
  for (int i = 0; i < nc; ++i) {
    if (index[i] < 0) continue;
    const auto& c = kin.contacts[i];
    const int row = problem_.row[index[i]];
    problem_.b[row] += coefficients_.normal[i] * std::min(c.zeta_n, 0.0);
    for (int k = 0; k < c.tangents; ++k) problem_.b[row + 1 + k] += coefficients_.tangential[i] * c.zeta_t[k];
  }
  velocity_scale_ = std::max(velocity_scale_, 1e-300);

  // Solve: Lemke when every contact is planar or frictionless, else the Coulomb solver.
  solution_.lambda.resize(m);
  solution_.y.resize(m);
  bool use_lemke = options_.solver == ImpactOptions::Solver::Lemke ||
                   (options_.solver == ImpactOptions::Solver::Automatic && !any_spatial);
  ContactSolveStatus status = ContactSolveStatus::Solved;
  if (m == 0) {
    solution_.residual = 0.0;
    solution_.iterations = 0;
  } else if (use_lemke) {
    status = lemke_.solve(problem_, solution_);
    if (!(solution_.residual <= options_.residual_tolerance)) use_lemke = false;  // fall back on Newton
  }
  if (m > 0 && !use_lemke) status = coulomb_.solve(problem_, solution_);
  r.used_lemke = use_lemke;
  r.residual = solution_.residual;
  r.iterations = solution_.iterations;
  // A solver may stop short of its own target (round-off) yet within ours: the residual decides.
  if (m > 0 && !(solution_.residual <= options_.residual_tolerance)) {
    throw ContactProblemFailure(detail::concat("impact problem has no solution within tolerance: solver status '",
                                               to_string(status), "', natural-map residual ", solution_.residual, " > ",
                                               options_.residual_tolerance, " with ", problem_.contacts,
                                               " contacts at x- = [", x_reported.transpose(), "]"));
  }

  // Identify the impulse mode from the solution.
  impulse_scale_ = m > 0 ? solution_.lambda.head(m).cwiseAbs().maxCoeff() : 0.0;
  impulse_scale_ = std::max(impulse_scale_, 1e-300);
  VecT<double, nq> v_plus_solver = v_minus;
  if (m > 0) v_plus_solver.noalias() += MinvWt * solution_.lambda.head(m);
  for (int i = 0; i < nc; ++i) {
    r.impulse_mode[i] = ImpulseMode{};
    r.post_mode[i] = ContactState::open();
    if (index[i] < 0) continue;
    const int row = problem_.row[index[i]];
    const int nt = kin.contacts[i].tangents;
    const double ln = solution_.lambda[row];
    // xi_t decides the impulse's role (the law acts on it); zeta_t^+ = xi_t - e_t zeta_t^-, the
    // velocity after the impact, decides the post-impact mode of a contact that stays closed.
    Eigen::Vector2d yt = Eigen::Vector2d::Zero();
    for (int k = 0; k < nt; ++k) yt[k] = solution_.y[row + 1 + k];
    const bool tangential_rest = yt.norm() <= options_.velocity_tolerance * velocity_scale_;
    const Eigen::Vector2d dir = tangential_rest ? Eigen::Vector2d::Zero() : Eigen::Vector2d(yt / yt.norm());
    Eigen::Vector2d zt_plus = yt;
    for (int k = 0; k < nt; ++k) zt_plus[k] -= coefficients_.tangential[i] * kin.contacts[i].zeta_t[k];
    const bool post_rest = zt_plus.norm() <= options_.velocity_tolerance * velocity_scale_;
    const Eigen::Vector2d post_dir = post_rest ? Eigen::Vector2d::Zero() : Eigen::Vector2d(zt_plus / zt_plus.norm());
    if (ln > options_.impulse_tolerance * impulse_scale_) {
      if (nt == 0)
        r.impulse_mode[i].role = ImpulseRole::Stick;  // frictionless: the normal row only
      else if (tangential_rest)
        r.impulse_mode[i].role = ImpulseRole::Stick;
      else
        r.impulse_mode[i] =
            ImpulseMode{ImpulseRole::Slip, nt == 1 ? Eigen::Vector2d(dir[0] > 0 ? 1.0 : -1.0, 0.0) : dir};
    }
    const double yn_plus = solution_.y[row] - coefficients_.normal[i] * std::min(kin.contacts[i].zeta_n, 0.0);
    if (yn_plus > options_.velocity_tolerance * velocity_scale_) continue;  // separating: open
    if (nt == 0)
      r.post_mode[i] = ContactState::slip(Eigen::Vector2d::Zero());
    else if (post_rest)
      r.post_mode[i] = ContactState::stick();
    else
      r.post_mode[i] =
          nt == 1 ? ContactState::slip_planar(post_dir[0] > 0 ? 1 : -1) : ContactState::slip(post_dir);
  }

  // The jump map of that mode gives v+ and the minimum-norm impulse. Where slipping contacts
  // are redundant, the velocity depends on how the impulse is shared and the minimum-norm
  // share need not be admissible (or its implicit slip directions may not exist): then the
  // solver's own impulse is returned.
  bool jump_map_ok = true;
  try {
    jump_.coefficients = &coefficients_;
    apply_jump_map(scene_, r.impulse_mode, x_minus, jump_, x_jump_);
  } catch (const NumericalFailure&) {
    jump_map_ok = false;
  }
  r.singular_delassus = m > 0 && problem_rank_ < m;
  r.minimum_norm_impulse = false;
  if (jump_map_ok) {
    const double v_scale = std::max(v_minus.cwiseAbs().maxCoeff(), v_plus_solver.cwiseAbs().maxCoeff());
    const bool same_velocity = (jump_.v_plus - v_plus_solver).cwiseAbs().maxCoeff() <= 1e-9 * std::max(v_scale, 1e-300);
    fill_from_jump_map(x_minus, index);
    const bool laws_hold = r.signorini_residual <= 1e-12 && r.coulomb_residual <= 1e-12;
    r.minimum_norm_impulse = same_velocity && laws_hold;
  }
  if (!r.minimum_norm_impulse) fill_from_solver(x_minus, index, v_plus_solver);
  r.kinetic_energy_plus = kinetic_energy(kin.M, VecT<double, nq>(r.x_plus.template tail<nq>()));
}

template <Scene S>
void ImpactSolver<S>::fill_from_jump_map(const VecT<double, nx>& x_minus, const std::array<int, nc>& index) {
  auto& r = result_;
  r.x_plus = x_jump_;
  for (int i = 0; i < nc; ++i) r.impulse[i] = jump_.impulse[i];
  compute_law_residuals(x_minus, index);
}

template <Scene S>
void ImpactSolver<S>::fill_from_solver(const VecT<double, nx>& x_minus, const std::array<int, nc>& index,
                                       const VecT<double, nq>& v_plus) {
  auto& r = result_;
  r.x_plus.template head<nq>() = x_minus.template head<nq>();
  r.x_plus.template tail<nq>() = v_plus;
  for (int i = 0; i < nc; ++i) {
    r.impulse[i] = ContactForce<double>{};
    if (index[i] < 0) continue;
    const int row = problem_.row[index[i]];
    r.impulse[i].normal = solution_.lambda[row];
    for (int k = 0; k < jump_.kin.contacts[i].tangents; ++k) r.impulse[i].tangent[k] = solution_.lambda[row + 1 + k];
  }
  compute_law_residuals(x_minus, index);
}

template <Scene S>
void ImpactSolver<S>::compute_law_residuals(const VecT<double, nx>& x_minus, const std::array<int, nc>& index) {
  (void)x_minus;
  auto& r = result_;
  const auto& kin = jump_.kin;
  const VecT<double, nq> v_plus = r.x_plus.template tail<nq>();
  double L = 0.0;
  for (int i = 0; i < nc; ++i)
    L = std::max({L, std::abs(r.impulse[i].normal), r.impulse[i].tangent.cwiseAbs().maxCoeff()});
  // Impulses far below the problem's own impulse scale (the impulse that changes a contact
  // velocity by V: V / max|D|) are round-off of the solve and do not set the scale (found by
  // fuzzing: a flat block sliding at 3 m/s with a normal velocity of -5.7e-159 m/s has impulses
  // of 1e-159 whose Coulomb balance holds to 1e-167 N s, 1e-8 of themselves).
  const int m = problem_.rows();
  if (m > 0) {
    const double delassus_scale = problem_.A.topLeftCorner(m, m).cwiseAbs().maxCoeff();
    if (delassus_scale > 0) L = std::max(L, velocity_scale_ / delassus_scale);
  }
  L = std::max(L, 1e-300);
  const double V = velocity_scale_;
  r.velocity_scale = V;
  r.impulse_scale = L;
  r.signorini_residual = 0.0;
  r.coulomb_residual = 0.0;
  for (int i = 0; i < nc; ++i) {
    const auto& c = kin.contacts[i];
    r.normal_velocity_minus[i] = c.zeta_n;
    r.normal_velocity_plus[i] = c.wn.dot(v_plus);
    r.tangent_velocity_plus[i].setZero();
    for (int k = 0; k < c.tangents; ++k) r.tangent_velocity_plus[i][k] = c.Wt.col(k).dot(v_plus);
    if (index[i] < 0) continue;
    const ContactSpec& spec = scene_.contact(i);
    const double ln = r.impulse[i].normal;
    const double yn = r.normal_velocity_plus[i] + coefficients_.normal[i] * std::min(c.zeta_n, 0.0);
    r.signorini_residual =
        std::max({r.signorini_residual, std::max(-ln, 0.0) / L, std::max(-yn, 0.0) / V, std::abs(ln * yn) / (L * V)});
    if (c.tangents == 0) continue;
    const Eigen::Vector2d lt = r.impulse[i].tangent;
    Eigen::Vector2d yt = r.tangent_velocity_plus[i];  // xi_t of the impact law
    for (int k = 0; k < c.tangents; ++k) yt[k] += coefficients_.tangential[i] * c.zeta_t[k];
    r.coulomb_residual = std::max(r.coulomb_residual, std::max(lt.norm() - spec.mu * ln, 0.0) / L);
    if (yt.norm() > options_.velocity_tolerance * V)
      r.coulomb_residual = std::max(r.coulomb_residual, (lt + spec.mu * ln * yt / yt.norm()).norm() / L);
  }
}

}  // namespace saltus
