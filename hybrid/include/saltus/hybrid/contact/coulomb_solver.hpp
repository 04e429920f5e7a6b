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
//
// This header declares; the definitions are in coulomb_solver.hxx. The library compiles them
// once for the contact bounds 1, 2, 4, 8, 16 and 32 (contact_bound, contact_problem.hpp;
// hybrid/src/contact_bound_*.cpp); they are declared extern below. For another bound, include
// <saltus/hybrid/contact/coulomb_solver.hxx>, which instantiates them on use.
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
  /// friction disks (up to 12 sides, fewer for MaxContacts > 4, none for MaxContacts > 21;
  /// detail::coulomb_restart_sides). The scenes' solvers have MaxContacts = contact_bound(nc).
  bool polyhedral_restarts = true;
};

namespace detail {
/// Sides of the largest polygon of CoulombSolver<MaxContacts>'s LCP restarts (0: none). The
/// LCP has (sides + 2) unknowns per contact and stores two square matrices of its size: at
/// most 64 unknowns (64 kB), or 6 per contact for many contacts, and never beyond Eigen's limit
/// for fixed-size storage (128 x 128 doubles).
constexpr int coulomb_restart_sides(int max_contacts) {
  const int budget = std::min(128, std::max(64, 6 * max_contacts));
  for (const int sides : {12, 8, 6, 4})
    if ((sides + 2) * max_contacts <= budget) return sides;
  return 0;
}
}  // namespace detail

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

  /// Solves p into out (lambda, y = A lambda + b, natural-map residual, iterations), from
  /// initial_guess (size p.rows()) if given, else from Gauss-Seidel sweeps from lambda = 0.
  /// Ends with IterationLimit and the best point met when the tolerance is not reached.
  /// Throws InvalidArgument for more than MaxContacts contacts, a tangent count other than
  /// 0, 1, 2, a negative or non-finite mu, or A, b or the guess not sized or not finite as
  /// the contacts declare.
  ContactSolveStatus solve(const Problem& p, Solution& out, const Vector* initial_guess = nullptr);

 private:
  // Sides of the largest polygon of the LCP restarts (detail::coulomb_restart_sides).
  static constexpr int max_sides = detail::coulomb_restart_sides(MaxContacts);
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

  static void validate(const Problem& p, const Vector* guess);

  // rho_k makes rho_k y and lambda commensurate block by block: 1 / (mean diagonal of A_kk),
  // the effective mass of the contact. Any positive rho gives the same zeros; this one keeps
  // the Newton matrix and the Gauss-Seidel steps well scaled under large mass ratios.
  void setup(const Problem& p);

  // Phi at lambda (y = A lambda + b given), and if asked one element of its generalised
  // Jacobian. Returns 0.5 ||Phi||^2.
  double natural_map(const Problem& p, const Vector& lambda, const Vector& y, Vector& phi,
                     Matrix* jac);

  // One damped semismooth Newton step from lambda_ (y_ = A lambda_ + b). Returns the ratio by
  // which it decreased 0.5 ||Phi||^2, or -1 when the line search found no sufficient decrease.
  double newton_step(const Problem& p);

  // dir_ = J^+ rhs_, allocation-free (linear_solve.hpp).
  void min_norm_solve();

  // One nonsmooth Gauss-Seidel sweep: each contact solves its own 1- to 3-dimensional problem
  // exactly with the others fixed (solve_contact), so that the fixed points of a sweep are
  // exactly the solutions of the whole problem.
  void sweep(const Problem& p);

  // The one-contact problem y = W l + c, Signorini and Coulomb, solved by cases: separation
  // (l = 0 as soon as c_n >= 0), sticking (y = 0), sliding (y_n = 0, l = l_n (1, -mu u) with
  // y_t = alpha u, alpha >= 0). With one tangent u = +-1; with two, u = (cos th, sin th) and
  // the sliding condition y_t x u = 0 is a scalar equation in th, bracketed on a grid and
  // solved by regula falsi. Returns false (l unchanged) when no case applies, which only
  // happens for a singular or indefinite W.
  static bool solve_contact(const Eigen::Matrix3d& W, const Eigen::Vector3d& c, int nt, double mu,
                            Eigen::Vector3d& l);

  // Fallback for a singular or indefinite block: normal step, then the tangential force
  // projected onto the disk of the new normal force, a few times over.
  static void approximate_contact(const Eigen::Matrix3d& W, const Eigen::Vector3d& c, int nt,
                                  double mu, Eigen::Vector3d& l);

  std::array<double, MaxContacts> rho_{};
  double best_residual_ = 0.0, rho_scale_ = 1.0;
  Vector lambda_, best_lambda_, y_, phi_, rhs_, dir_, work_, trial_, ytrial_, phitrial_;
  Matrix jac_;
  Eigen::CompleteOrthogonalDecomposition<Matrix> cod_;
  std::conditional_t<(max_sides > 0), detail::PolyhedralContactLcp<MaxContacts, max_sides>,
                     detail::NoPolyhedralLcp<MaxContacts>>
      poly_;
};

// Compiled once in the library for the contact bounds 1, 2, 4, 8, 16, 32 (contact_bound), with
// the LCPs of their polygon restarts (none for 32 contacts: coulomb_restart_sides(32) = 0), in
// hybrid/src/contact_bound_*.cpp.
#ifndef SALTUS_CONTACT_NO_EXTERN_TEMPLATES
extern template class detail::PolyhedralContactLcp<1, detail::coulomb_restart_sides(1)>;
extern template class detail::PolyhedralContactLcp<2, detail::coulomb_restart_sides(2)>;
extern template class detail::PolyhedralContactLcp<4, detail::coulomb_restart_sides(4)>;
extern template class detail::PolyhedralContactLcp<8, detail::coulomb_restart_sides(8)>;
extern template class detail::PolyhedralContactLcp<16, detail::coulomb_restart_sides(16)>;
extern template class CoulombSolver<1>;
extern template class CoulombSolver<2>;
extern template class CoulombSolver<4>;
extern template class CoulombSolver<8>;
extern template class CoulombSolver<16>;
extern template class CoulombSolver<32>;
#endif

}  // namespace saltus
