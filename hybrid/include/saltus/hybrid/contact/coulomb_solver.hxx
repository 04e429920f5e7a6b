// Definitions of coulomb_solver.hpp (the method and the interface are documented there).
//
// The library compiles these once for the bounds declared extern in coulomb_solver.hpp.
// Include this file, not coulomb_solver.hpp, to use another bound (the solver is then
// instantiated on use).
#pragma once

#include <saltus/hybrid/contact/coulomb_solver.hpp>
#include <saltus/hybrid/contact/lemke.hxx>

namespace saltus {

template <int MaxContacts>
ContactSolveStatus CoulombSolver<MaxContacts>::solve(const Problem& p, Solution& out,
                                                       const Vector* initial_guess) {
  validate(p, initial_guess);
  const int m = p.rows();
  setup(p);
  out.iterations = 0;

  // No approaching contact: lambda = 0 is a solution (the friction radius is then 0).
  bool trivial = true;
  for (int k = 0; k < p.contacts; ++k) trivial = trivial && p.b[p.row[k]] >= 0.0;
  if (trivial || m == 0) {
    out.lambda.setZero(m);
    out.y = p.b;
    out.residual = natural_map_residual(p, out.lambda, out.y);
    out.status = ContactSolveStatus::Solved;
    return out.status;
  }

  if (initial_guess != nullptr)
    lambda_ = *initial_guess;
  else
    lambda_.setZero(m);

  int iterations = 0;
  best_residual_ = std::numeric_limits<double>::infinity();
  best_lambda_ = lambda_;
  // A guess from the caller (the previous step's solution) is usually better than what
  // Gauss-Seidel would make of it: Newton starts from it directly.
  const int warm =
      initial_guess != nullptr ? 0 : std::min(options.warm_start_sweeps, options.max_iterations);
  for (int s = 0; s < warm; ++s) sweep(p);
  iterations += warm;

  bool spatial = false;
  for (int k = 0; k < p.contacts; ++k) spatial = spatial || (p.tangents[k] == 2 && p.mu[k] > 0);
  ContactSolveStatus status = ContactSolveStatus::IterationLimit;
  int stalls = 0, slow = 0, restarts = 0, lcp_attempts = 0;
  rho_scale_ = 1.0;
  double residual_at_stall = std::numeric_limits<double>::infinity();
  while (true) {
    y_.noalias() = p.A * lambda_;
    y_ += p.b;
    const double res = natural_map_residual(p, lambda_, y_);
    if (res < best_residual_) {  // NaN never compares less: a NaN point is never kept
      best_residual_ = res;
      best_lambda_ = lambda_;
    }
    if (best_residual_ <= options.tolerance) {
      status = ContactSolveStatus::Solved;
      break;
    }
    if (iterations >= options.max_iterations) break;

    ++iterations;
    const double decrease = newton_step(p);
    // Near a solution the semismooth Newton method converges superlinearly: a run of steps
    // that do not halve ||Phi||^2 is damped crawling, as bad as a failed line search.
    if (decrease >= 0.0 && (decrease <= 0.5 || ++slow < 5)) {
      if (decrease <= 0.5) slow = 0;
      continue;
    }
    slow = 0;

    // Stalled: the line search failed, or crawls towards a kink of the projections where
    // ||Phi||^2 has a local minimum that is no solution; or the residual is at round-off.
    if (best_residual_ < 0.5 * residual_at_stall) {
      residual_at_stall = best_residual_;
      stalls = 0;
    } else if (++stalls >= options.max_stalls) {
      break;
    }
    ++iterations;
    // Without spatial contacts every polygon gives the same (exact) LCP: one attempt.
    while (lcp_attempts < static_cast<int>(polygons.size()) &&
           (polygons[lcp_attempts].first > max_sides || (lcp_attempts > 0 && !spatial)))
      ++lcp_attempts;
    if (options.polyhedral_restarts && lcp_attempts < static_cast<int>(polygons.size())) {
      // Restart from the solution of the LCP in which a polygon replaces each friction disk:
      // Lemke's method finds it whenever the problem is mechanical, exact for planar
      // contacts, and Newton then only has to correct the polygon's error. Solutions need
      // not be unique, and the polyhedral problem may have some near which the disk problem
      // has none: the next stall tries another polygon.
      const auto [dirs, rotation] = polygons[lcp_attempts++];
      poly_.solve(p, dirs, detail::LemkeOptions{}, trial_, rotation * 3.14159265358979323846);
      if (trial_.allFinite()) {
        lambda_ = trial_;
        rho_scale_ = 1.0;
        continue;
      }
    }
    // Then Gauss-Seidel sweeps, which move the point without needing a direction, and other
    // weights rho, which move the spurious stationary points of ||Phi||^2 (not its zeros).
    ++restarts;
    rho_scale_ = rho_factors[restarts % rho_factors.size()];
    lambda_ = best_lambda_;
    const int sweeps = std::min(options.fallback_sweeps, options.max_iterations - iterations);
    for (int s = 0; s < sweeps; ++s) sweep(p);
    iterations += sweeps;
    if (!lambda_.allFinite()) lambda_ = best_lambda_;
  }

  out.lambda = best_lambda_;
  out.y.noalias() = p.A * out.lambda;
  out.y += p.b;
  out.residual = natural_map_residual(p, out.lambda, out.y);
  out.iterations = iterations;
  out.status = status;
  return status;
}

template <int MaxContacts>
void CoulombSolver<MaxContacts>::validate(const Problem& p, const Vector* guess) {
  SALTUS_REQUIRE(p.contacts >= 0 && p.contacts <= MaxContacts, 
                "CoulombSolver: ", p.contacts, " contacts, at most ", MaxContacts);
  for (int k = 0; k < p.contacts; ++k) {
    SALTUS_REQUIRE(p.tangents[k] >= 0 && p.tangents[k] <= 2, 
                  "CoulombSolver: contact ", k, " has ", p.tangents[k],
                  " tangents (0, 1 or 2 expected)");
    SALTUS_REQUIRE(std::isfinite(p.mu[k]) && p.mu[k] >= 0.0, 
                  "CoulombSolver: contact ", k, " has friction coefficient mu = ", p.mu[k]);
  }
  const int m = p.rows();
  SALTUS_REQUIRE(p.A.rows() == m && p.A.cols() == m && p.b.size() == m, 
                "CoulombSolver: A is ", p.A.rows(), "x", p.A.cols(), " and b has ",
                p.b.size(), " rows, the contacts declare ", m);
  SALTUS_REQUIRE(p.A.allFinite() && p.b.allFinite(), 
                "CoulombSolver: A or b is not finite");
  if (guess != nullptr)
    SALTUS_REQUIRE(guess->size() == m && guess->allFinite(), 
                  "CoulombSolver: the initial guess has ", guess->size(),
                  " rows (or non-finite entries), the problem has ", m);
}

template <int MaxContacts>
void CoulombSolver<MaxContacts>::setup(const Problem& p) {
  const double global = contact_problem_scale(p);
  for (int k = 0; k < p.contacts; ++k) {
    const int nk = 1 + p.tangents[k];
    const double a = p.A.diagonal().segment(p.row[k], nk).cwiseAbs().sum() / nk;
    rho_[k] = a > 0.0 ? 1.0 / a : global;
  }
}

template <int MaxContacts>
double CoulombSolver<MaxContacts>::natural_map(const Problem& p, const Vector& lambda,
                                                const Vector& y, Vector& phi, Matrix* jac) {
  const int m = p.rows();
  phi.resize(m);
  if (jac != nullptr) jac->setZero(m, m);
  for (int k = 0; k < p.contacts; ++k) {
    const int r = p.row[k], nt = p.tangents[k];
    const double rho = rho_[k] * rho_scale_;
    const double ln = lambda[r];
    // Normal: on the active branch Phi_n = rho y_n, otherwise Phi_n = lambda_n. The kink
    // lambda_n = rho y_n goes to the inactive side, whose Jacobian row is never singular.
    if (ln - rho * y[r] > 0.0) {
      phi[r] = rho * y[r];
      if (jac != nullptr) jac->row(r) = rho * p.A.row(r);
    } else {
      phi[r] = ln;
      if (jac != nullptr) (*jac)(r, r) = 1.0;
    }
    if (nt == 0) continue;
    const int t = r + 1;
    const double radius = p.mu[k] * std::max(ln, 0.0);
    Eigen::Vector2d lt = Eigen::Vector2d::Zero(), z = Eigen::Vector2d::Zero();
    for (int j = 0; j < nt; ++j) {
      lt[j] = lambda[t + j];
      z[j] = lambda[t + j] - rho * y[t + j];
    }
    const double nz = z.norm();
    if (nz <= radius) {
      // Sticking (interior of the disk): the projection is the identity.
      for (int j = 0; j < nt; ++j) phi[t + j] = rho * y[t + j];
      if (jac != nullptr) jac->middleRows(t, nt) = rho * p.A.middleRows(t, nt);
      continue;
    }
    // Sliding: proj = radius u, u = z / ||z||. d proj / dz = (radius / ||z||)(I - u u^T) and
    // d proj / d lambda_n = mu u (radius > 0 only when lambda_n > 0).
    const Eigen::Vector2d u = z / nz;  // nz > radius >= 0
    for (int j = 0; j < nt; ++j) phi[t + j] = lt[j] - radius * u[j];
    if (jac == nullptr) continue;
    for (int j = 0; j < nt; ++j) (*jac)(t + j, t + j) = 1.0;
    if (radius <= 0.0) continue;
    Eigen::Matrix2d P = Eigen::Matrix2d::Zero();
    if (nt == 2) P = (radius / nz) * (Eigen::Matrix2d::Identity() - u * u.transpose());
    // d Phi_t = d lambda_t - P (d lambda_t - rho A_t d lambda) - mu u d lambda_n
    for (int i = 0; i < nt; ++i) {
      for (int j = 0; j < nt; ++j) {
        if (P(i, j) == 0.0) continue;
        jac->row(t + i) += (rho * P(i, j)) * p.A.row(t + j);
        (*jac)(t + i, t + j) -= P(i, j);
      }
      (*jac)(t + i, r) -= p.mu[k] * u[i];
    }
  }
  return 0.5 * phi.squaredNorm();
}

template <int MaxContacts>
double CoulombSolver<MaxContacts>::newton_step(const Problem& p) {
  const double f0 = natural_map(p, lambda_, y_, phi_, &jac_);
  if (!(f0 > 0.0)) return -1.0;
  // Minimum-norm least-squares direction: exact Newton where the Jacobian is regular, and
  // still a descent direction (for the consistent part) where it is not.
  cod_.setThreshold(1e-12);
  cod_.compute(jac_);
  rhs_ = -phi_;
  min_norm_solve();
  if (!dir_.allFinite()) return -1.0;
  // Armijo on f: along a Newton direction f'(0) = -||Phi||^2 = -2 f0 (the projected part of
  // Phi in the singular case, hence the small sigma).
  constexpr double sigma = 1e-4;
  double t = 1.0;
  for (int ls = 0; ls < 30; ++ls, t *= 0.5) {
    trial_ = lambda_ + t * dir_;
    ytrial_.noalias() = p.A * trial_;
    ytrial_ += p.b;
    const double f = natural_map(p, trial_, ytrial_, phitrial_, nullptr);
    if (f <= (1.0 - 2.0 * sigma * t) * f0) {
      lambda_ = trial_;
      return f / f0;
    }
  }
  return -1.0;
}

template <int MaxContacts>
void CoulombSolver<MaxContacts>::min_norm_solve() {
  saltus::min_norm_solve(cod_, rhs_, dir_, work_);
}

template <int MaxContacts>
void CoulombSolver<MaxContacts>::sweep(const Problem& p) {
  for (int k = 0; k < p.contacts; ++k) {
    const int r = p.row[k], nt = p.tangents[k], nk = 1 + nt;
    Eigen::Matrix3d W = Eigen::Matrix3d::Zero();
    Eigen::Vector3d c = Eigen::Vector3d::Zero(), l = Eigen::Vector3d::Zero();
    W.topLeftCorner(nk, nk) = p.A.block(r, r, nk, nk);
    for (int i = 0; i < nk; ++i) {
      l[i] = lambda_[r + i];
      c[i] = p.b[r + i] + p.A.row(r + i).dot(lambda_);
    }
    c -= W * l;  // what b and the other contacts contribute to y_k
    if (!solve_contact(W, c, nt, p.mu[k], l)) approximate_contact(W, c, nt, p.mu[k], l);
    for (int i = 0; i < nk; ++i) lambda_[r + i] = l[i];
  }
}

template <int MaxContacts>
bool CoulombSolver<MaxContacts>::solve_contact(const Eigen::Matrix3d& W, const Eigen::Vector3d& c,
                                                int nt, double mu, Eigen::Vector3d& l) {
  if (c[0] >= 0.0) {
    l.setZero();
    return true;
  }
  if (nt == 0 || mu == 0.0) {
    if (!(W(0, 0) > 0.0)) return false;
    l.setZero();
    l[0] = -c[0] / W(0, 0);
    return true;
  }
  // Sticking.
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  bool regular = false;
  if (nt == 1) {
    const Eigen::Matrix2d W2 = W.topLeftCorner<2, 2>();
    const double det = W2.determinant();
    if (std::abs(det) > 1e-13 * W2.squaredNorm()) {
      s.head<2>() = W2.inverse() * (-c.head<2>());
      regular = true;
    }
  } else {
    const double det = W.determinant();
    const double wn = W.norm();
    if (std::abs(det) > 1e-13 * wn * wn * wn) {
      s = W.inverse() * (-c);
      regular = true;
    }
  }
  if (regular && s[0] >= 0.0 && s.tail<2>().norm() <= mu * s[0]) {
    l = s;
    return true;
  }
  // Sliding with one tangent: u = +1 or -1.
  if (nt == 1) {
    for (const double u : {1.0, -1.0}) {
      const double wn = W(0, 0) - mu * u * W(0, 1);
      if (!(wn > 0.0)) continue;
      const double ln = -c[0] / wn;
      const double yt = ln * (W(1, 0) - mu * u * W(1, 1)) + c[1];
      if (yt * u >= 0.0) {
        l << ln, -mu * u * ln, 0.0;
        return true;
      }
    }
    return false;
  }
  // Sliding with two tangents.
  struct Eval {
    bool valid;
    double g, dot, ln;
  };
  auto eval = [&](double th) {
    const Eigen::Vector2d u(std::cos(th), std::sin(th));
    const Eigen::Vector3d v(1.0, -mu * u[0], -mu * u[1]);
    const Eigen::Vector3d Wv = W * v;
    if (!(Wv[0] > 0.0)) return Eval{false, 0.0, 0.0, 0.0};
    const double ln = -c[0] / Wv[0];
    const Eigen::Vector2d yt = ln * Wv.tail<2>() + c.tail<2>();
    return Eval{true, yt[0] * u[1] - yt[1] * u[0], yt.dot(u), ln};
  };
  // The grid is visited from the interval of a guessed slip direction outwards, which
  // brackets the usual root at once: opposite to the previous friction force (Gauss-Seidel
  // sweeps change it little), else to the sticking force, else along the free slip.
  Eigen::Vector2d guess = -l.tail<2>();
  if (!(guess.squaredNorm() > 0.0) && regular) guess = -s.tail<2>();
  if (!(guess.squaredNorm() > 0.0))
    guess = c.tail<2>() - (W(0, 0) > 0.0 ? c[0] / W(0, 0) : 0.0) * W.block<2, 1>(1, 0);
  constexpr int grid = 32;
  constexpr double two_pi = 2.0 * 3.14159265358979323846;
  constexpr double step = two_pi / grid;
  const double th0 = std::atan2(guess[1], guess[0]);  // atan2(0, 0) = 0: no preference
  const int i0 = static_cast<int>(std::floor((th0 < 0.0 ? th0 + two_pi : th0) / step));
  for (int j = 0; j < grid; ++j) {
    const int i = ((i0 + (j % 2 == 0 ? j / 2 : -(j + 1) / 2)) % grid + grid) % grid;
    double a = i * step, b = (i + 1) * step;
    const Eval ea = eval(a), eb = eval(b);
    const bool bracket = ea.valid && eb.valid && (ea.g <= 0.0) != (eb.g <= 0.0) &&
                         (ea.dot > 0.0 || eb.dot > 0.0);
    if (bracket) {
      // Illinois variant of regula falsi: superlinear, and never leaves the bracket.
      Eval fa = ea, fb = eb, fx = ea;
      double x = a;
      for (int it = 0; it < 100; ++it) {
        x = b - fb.g * (b - a) / (fb.g - fa.g);
        fx = eval(x);
        if (!fx.valid || fx.g == 0.0) break;
        if ((fx.g < 0.0) != (fb.g < 0.0)) {
          a = b;
          fa = fb;
        } else {
          fa.g *= 0.5;
        }
        b = x;
        fb = fx;
        if (std::abs(b - a) < 1e-15) break;
      }
      if (fx.valid && fx.dot >= 0.0 && fx.ln >= 0.0) {
        l << fx.ln, -mu * fx.ln * std::cos(x), -mu * fx.ln * std::sin(x);
        return true;
      }
    }
  }
  return false;
}

template <int MaxContacts>
void CoulombSolver<MaxContacts>::approximate_contact(const Eigen::Matrix3d& W,
                                                      const Eigen::Vector3d& c, int nt, double mu,
                                                      Eigen::Vector3d& l) {
  const double wnn = W(0, 0);
  const double wt = nt > 0 ? W.block(1, 1, nt, nt).norm() : 0.0;
  for (int it = 0; it < (nt == 0 ? 1 : 5); ++it) {
    if (wnn > 0.0) l[0] = std::max(0.0, l[0] - (W.row(0).dot(l) + c[0]) / wnn);
    if (nt == 0) break;
    Eigen::Vector2d lt = l.tail<2>();
    if (wt > 0.0) {
      Eigen::Vector2d yt = (W * l + c).tail<2>();
      if (nt == 1) yt[1] = 0.0;
      lt -= yt / wt;
    }
    project_onto_disk(lt, mu * l[0]);
    l.tail<2>() = lt;
  }
}

}  // namespace saltus
