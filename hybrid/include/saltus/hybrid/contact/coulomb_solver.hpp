// Solver of the contact problem with any mix of frictionless, planar and spatial contacts.
//
// The Signorini and Coulomb laws of contact k hold exactly when its Alart-Curnier natural map
// vanishes (Alart & Curnier 1991; thesis A.53, A.57): with y = A lambda + b and rho_k > 0,
//
//   Phi_n(lambda) = lambda_n - max(0, lambda_n - rho_k y_n)
//   Phi_t(lambda) = lambda_t - proj_{D(mu max(lambda_n, 0))}(lambda_t - rho_k y_t)
//
// where D(r) is the disk of radius r. The radius is taken at the current lambda_n, not
// projected together with it onto the cone: this is the non-associated Coulomb law, not De
// Saxce's modified cone. Phi is piecewise smooth (strongly semismooth), so Phi = 0 is solved by
// a semismooth Newton method (Qi & Sun 1993) on an element of the generalised Jacobian, with a
// backtracking line search on 0.5 ||Phi||^2.
//
// A = W M^{-1} W^T is singular for redundant contacts, and then so is the Newton matrix (a
// whole set of lambdas gives the same velocities). Its solutions are non-isolated but the
// system is consistent, so each Newton step is the minimum-norm least-squares solution given by
// a complete orthogonal decomposition (rank revealing).
//
// Globalisation. Newton starts from a few nonsmooth Gauss-Seidel sweeps (Jean & Moreau's NSGS,
// each contact's 1- to 3-dimensional problem solved exactly with the others fixed). The merit
// 0.5 ||Phi||^2 has local minima that are no solutions, at kinks of the projections, where the
// damped Newton method stalls or crawls (a few percent of our random test problems with
// redundant contacts meet one). Newton then restarts from the solution of the LCP in which a
// polygon replaces each friction disk (detail::PolyhedralContactLcp, solved by Lemke's method,
// which Anitescu & Potra 1997 show always succeeds on mechanical problems): exact for planar
// contacts, within the polygon's error for spatial ones. If that stalls too, other polygons,
// then Gauss-Seidel sweeps with other weights rho (which move the spurious minima, not the
// zeros). On random spatial problems about 1 in 10^4 still ends above 1e-12.
//
// Everything is stored in members of fixed maximum size: solve() never allocates.
#pragma once

#include <saltus/hybrid/contact/contact_problem.hpp>
#include <saltus/hybrid/contact/linear_solve.hpp>
#include <saltus/hybrid/vocabulary/errors.hpp>
#include <saltus/hybrid/contact/lemke.hpp>

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/QR>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

namespace saltus {

/// Options of CoulombSolver (any MaxContacts).
struct CoulombSolverOptions {
  /// Target relative natural-map residual (natural_map_residual).
  double tolerance = 1e-14;
  /// Budget of Newton steps, Gauss-Seidel sweeps and LCP restarts (one each); past it the
  /// solve ends with IterationLimit and the best point found.
  int max_iterations = 300;
  /// Gauss-Seidel sweeps before the first Newton step, and after each stalled one.
  int warm_start_sweeps = 4;
  int fallback_sweeps = 10;
  /// Stalls of Newton's method in a row that do not halve the best residual before giving
  /// up (the residual then sits at the round-off level of the problem, above the tolerance).
  int max_stalls = 10;
  /// Restart a stalled Newton method from solutions of LCPs in which polygons replace the
  /// friction disks (up to 12 sides, fewer for MaxContacts > 4, none for MaxContacts > 21).
  bool polyhedral_restarts = true;
};

template <int MaxContacts>
class CoulombSolver {
 public:
  using Problem = ContactProblem<MaxContacts>;
  using Solution = ContactSolution<MaxContacts>;
  using Vector = typename Problem::Vector;
  using Matrix = typename Problem::Matrix;

  using Options = CoulombSolverOptions;


  CoulombSolver() = default;
  explicit CoulombSolver(const Options& o) : options(o) {}

  Options options;

  ContactSolveStatus solve(const Problem& p, Solution& out, const Vector* initial_guess = nullptr) {
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

 private:
  // Sides of the largest polygon of the LCP restarts. The LCP has (sides + 2) unknowns per
  // contact and stores two square matrices of its size: at most 64 unknowns (64 kB), or
  // 6 per contact for many contacts, and never beyond Eigen's limit for fixed-size storage
  // (128 x 128 doubles).
  static constexpr int max_sides = [] {
    const int budget = std::min(128, std::max(64, 6 * MaxContacts));
    for (const int sides : {12, 8, 6, 4})
      if ((sides + 2) * MaxContacts <= budget) return sides;
    return 0;
  }();
  // (sides, rotation / pi) of the polygons of the LCP restarts, tried in turn; those with more
  // than max_sides sides are skipped.
  static constexpr std::array<std::pair<int, double>, 9> polygons{{{8, 0.0},
                                                                   {12, 0.0},
                                                                   {8, 1.0 / 8},
                                                                   {12, 1.0 / 12},
                                                                   {6, 0.0},
                                                                   {12, 0.37},
                                                                   {8, 0.29},
                                                                   {12, 0.71},
                                                                   {4, 0.0}}};
  static constexpr std::array<double, 7> rho_factors{1.0, 0.1, 10.0, 0.01, 100.0, 0.3, 3.0};

  static void validate(const Problem& p, const Vector* guess) {
    SALTUS_DEMAND(p.contacts >= 0 && p.contacts <= MaxContacts, InvalidArgument,
                  "CoulombSolver: ", p.contacts, " contacts, at most ", MaxContacts);
    for (int k = 0; k < p.contacts; ++k) {
      SALTUS_DEMAND(p.tangents[k] >= 0 && p.tangents[k] <= 2, InvalidArgument,
                    "CoulombSolver: contact ", k, " has ", p.tangents[k],
                    " tangents (0, 1 or 2 expected)");
      SALTUS_DEMAND(std::isfinite(p.mu[k]) && p.mu[k] >= 0.0, InvalidArgument,
                    "CoulombSolver: contact ", k, " has friction coefficient mu = ", p.mu[k]);
    }
    const int m = p.rows();
    SALTUS_DEMAND(p.A.rows() == m && p.A.cols() == m && p.b.size() == m, InvalidArgument,
                  "CoulombSolver: A is ", p.A.rows(), "x", p.A.cols(), " and b has ",
                  p.b.size(), " rows, the contacts declare ", m);
    SALTUS_DEMAND(p.A.allFinite() && p.b.allFinite(), InvalidArgument,
                  "CoulombSolver: A or b is not finite");
    if (guess != nullptr)
      SALTUS_DEMAND(guess->size() == m && guess->allFinite(), InvalidArgument,
                    "CoulombSolver: the initial guess has ", guess->size(),
                    " rows (or non-finite entries), the problem has ", m);
  }

  // rho_k makes rho_k y and lambda commensurate block by block: 1 / (mean diagonal of A_kk),
  // the effective mass of the contact. Any positive rho gives the same zeros; this one keeps
  // the Newton matrix and the Gauss-Seidel steps well scaled under large mass ratios.
  void setup(const Problem& p) {
    const double global = contact_problem_scale(p);
    for (int k = 0; k < p.contacts; ++k) {
      const int nk = 1 + p.tangents[k];
      const double a = p.A.diagonal().segment(p.row[k], nk).cwiseAbs().sum() / nk;
      rho_[k] = a > 0.0 ? 1.0 / a : global;
    }
  }

  // Phi at lambda (y = A lambda + b given), and if asked one element of its generalised
  // Jacobian. Returns 0.5 ||Phi||^2.
  double natural_map(const Problem& p, const Vector& lambda, const Vector& y, Vector& phi,
                     Matrix* jac) {
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

  // One damped semismooth Newton step from lambda_ (y_ = A lambda_ + b). Returns the ratio by
  // which it decreased 0.5 ||Phi||^2, or -1 when the line search found no sufficient decrease.
  double newton_step(const Problem& p) {
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

  // dir_ = J^+ rhs_, allocation-free (linear_solve.hpp).
  void min_norm_solve() { saltus::min_norm_solve(cod_, rhs_, dir_, work_); }

  // One nonsmooth Gauss-Seidel sweep: each contact solves its own 1- to 3-dimensional problem
  // exactly with the others fixed (solve_contact), so that the fixed points of a sweep are
  // exactly the solutions of the whole problem.
  void sweep(const Problem& p) {
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

  // The one-contact problem y = W l + c, Signorini and Coulomb, solved by cases: separation
  // (l = 0 as soon as c_n >= 0), sticking (y = 0), sliding (y_n = 0, l = l_n (1, -mu u) with
  // y_t = alpha u, alpha >= 0). With one tangent u = +-1; with two, u = (cos th, sin th) and
  // the sliding condition y_t x u = 0 is a scalar equation in th, bracketed on a grid and
  // solved by regula falsi. Returns false (l unchanged) when no case applies, which only
  // happens for a singular or indefinite W.
  static bool solve_contact(const Eigen::Matrix3d& W, const Eigen::Vector3d& c, int nt, double mu,
                            Eigen::Vector3d& l) {
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

  // Fallback for a singular or indefinite block: normal step, then the tangential force
  // projected onto the disk of the new normal force, a few times over.
  static void approximate_contact(const Eigen::Matrix3d& W, const Eigen::Vector3d& c, int nt,
                                  double mu, Eigen::Vector3d& l) {
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

  std::array<double, MaxContacts> rho_{};
  double best_residual_ = 0.0, rho_scale_ = 1.0;
  Vector lambda_, best_lambda_, y_, phi_, rhs_, dir_, work_, trial_, ytrial_, phitrial_;
  Matrix jac_;
  Eigen::CompleteOrthogonalDecomposition<Matrix> cod_;
  std::conditional_t<(max_sides > 0), detail::PolyhedralContactLcp<MaxContacts, max_sides>,
                     detail::NoPolyhedralLcp<MaxContacts>>
      poly_;
};

}  // namespace saltus
