// The contact problem in Delassus form, shared by impacts (velocity level, thesis 2.27-2.32)
// and by the choice of a consistent contact mode (acceleration level, thesis 2.20-2.23).
//
//   y = A lambda + b,
//
// lambda and y stacked per contact k as [normal, tangents (0, 1 or 2)], with for every contact
//   Signorini / Poisson:  0 <= y_n  _|_  lambda_n >= 0                          (2.11, 2.28)
//   Coulomb (tangents>0): ||lambda_t|| <= mu lambda_n, and
//                         y_t != 0  =>  lambda_t = -mu lambda_n y_t / ||y_t||    (2.15-2.16, 2.29-2.30)
// Restitution is folded into b by the caller (y_n = zeta_n^+ + e zeta_n^-). A contact whose slip
// direction is prescribed (already slipping at acceleration level) is passed with 0 tangents and
// its friction folded into the columns of A, which then is not symmetric.
//
// A = W M^{-1} W^T is symmetric positive semidefinite for impacts; it is singular when contacts
// are redundant (a box landing flat), which every solver here must accept.
#pragma once

#include <saltus/hybrid/vocabulary/errors.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>

namespace saltus {

/// Contact-count bound of the contact numerics for a scene with nc contacts: the smallest of
/// 1, 2, 4, 8, 16, 32 that is >= nc. The solvers (LemkeSolver, CoulombSolver, lemke.hpp and
/// coulomb_solver.hpp) are compiled once in the library for these bounds, and a problem of
/// ContactProblem<contact_bound(nc)> holds nc contacts or fewer (`contacts` says how many).
/// Larger: nc itself, instantiated on use from the header-only definitions (include lemke.hxx
/// and coulomb_solver.hxx).
///
/// Defining SALTUS_CONTACT_NO_EXTERN_TEMPLATES before including the contact headers drops
/// their extern template declarations: with the .hxx files included, every bound is then
/// instantiated in the including translation unit (test_contact_solvers does so to compile
/// the solvers with EIGEN_RUNTIME_NO_MALLOC).
inline constexpr int contact_bound(int nc) {
  return nc <= 1 ? 1 : nc <= 2 ? 2 : nc <= 4 ? 4 : nc <= 8 ? 8 : nc <= 16 ? 16 : nc <= 32 ? 32 : nc;
}

/// A contact problem of at most MaxContacts contacts (see the file comment); A and b are
/// bounded by 3 MaxContacts rows and sized to the rows of the declared contacts.
template <int MaxContacts>
struct ContactProblem {
  static constexpr int max_rows = 3 * MaxContacts;
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, max_rows, max_rows>;
  using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, max_rows, 1>;

  int contacts = 0;                        ///< number of contacts in this problem
  std::array<int, MaxContacts> tangents{};  ///< 0, 1 or 2 per contact
  std::array<double, MaxContacts> mu{};     ///< Coulomb coefficient per contact
  std::array<int, MaxContacts> row{};       ///< row of contact k's normal component
  Matrix A;                                ///< m x m, m = sum (1 + tangents)
  Vector b;                                ///< m

  int rows() const { return contacts == 0 ? 0 : row[contacts - 1] + 1 + tangents[contacts - 1]; }

  /// Clears the problem and declares its contacts; A and b are sized (not filled).
  void reset() { contacts = 0; }
  int add_contact(int nt, double friction) {
    SALTUS_INVARIANT(contacts >= 0 && contacts < MaxContacts, "a contact problem holds at most its bound of contacts");
    const int r = rows();
    tangents[contacts] = nt;
    mu[contacts] = friction;
    row[contacts] = r;
    ++contacts;
    return contacts - 1;
  }
  void resize() {
    const int m = rows();
    A.resize(m, m);
    b.resize(m);
  }
};

enum class ContactSolveStatus { Solved, NoSolution, IterationLimit };

inline const char* to_string(ContactSolveStatus s) {
  switch (s) {
    case ContactSolveStatus::Solved: return "solved";
    case ContactSolveStatus::NoSolution: return "no solution (ray termination)";
    case ContactSolveStatus::IterationLimit: return "iteration limit reached";
  }
  return "?";
}

template <int MaxContacts>
struct ContactSolution {
  using Vector = typename ContactProblem<MaxContacts>::Vector;
  Vector lambda;  ///< stacked forces or impulses
  Vector y;       ///< A lambda + b
  double residual = 0.0;  ///< natural-map residual, relative (see natural_map_residual)
  int iterations = 0;
  ContactSolveStatus status = ContactSolveStatus::Solved;
};

/// Scale of the problem used to make residuals relative: r = m / trace(A) (an effective mass,
/// units force/velocity or impulse/velocity), so that r * y has the units of lambda.
template <int MaxContacts>
double contact_problem_scale(const ContactProblem<MaxContacts>& p) {
  const int m = p.rows();
  const double tr = m > 0 ? p.A.diagonal().cwiseAbs().sum() : 0.0;
  return tr > 0.0 ? m / tr : 1.0;
}

/// Euclidean projection onto the disk {||x|| <= radius} (radius clipped at 0).
template <class Derived>
void project_onto_disk(Eigen::MatrixBase<Derived>& x, double radius) {
  radius = std::max(radius, 0.0);
  const double n = x.norm();
  if (n > radius) {
    if (n > 0.0)
      x *= radius / n;
    else
      x.setZero();
  }
}

/// Natural-map (Alart-Curnier) residual of a candidate (lambda, y):
///   r_n = lambda_n - max(0, lambda_n - rho y_n)
///   r_t = lambda_t - proj_{D(mu max(lambda_n, 0))}(lambda_t - rho y_t)
/// It is zero exactly when the Signorini and Coulomb laws hold (thesis A.53, A.57). Returned
/// relative: ||r||_inf / (||lambda||_inf + rho ||b||_inf + tiny), rho = contact_problem_scale.
template <int MaxContacts, class VecL, class VecY>
double natural_map_residual(const ContactProblem<MaxContacts>& p, const VecL& lambda, const VecY& y) {
  const double rho = contact_problem_scale(p);
  double rmax = 0.0;
  for (int k = 0; k < p.contacts; ++k) {
    const int r = p.row[k];
    const double ln = lambda[r];
    rmax = std::max(rmax, std::abs(ln - std::max(0.0, ln - rho * y[r])));
    const int nt = p.tangents[k];
    if (nt > 0) {
      Eigen::Vector2d lt = Eigen::Vector2d::Zero(), z = Eigen::Vector2d::Zero();
      for (int j = 0; j < nt; ++j) {
        lt[j] = lambda[r + 1 + j];
        z[j] = lambda[r + 1 + j] - rho * y[r + 1 + j];
      }
      project_onto_disk(z, p.mu[k] * std::max(ln, 0.0));
      rmax = std::max(rmax, (lt - z).cwiseAbs().maxCoeff());
    }
  }
  const int m = p.rows();
  const double scale = (m > 0 ? lambda.head(m).cwiseAbs().maxCoeff() : 0.0) +
                       rho * (m > 0 ? p.b.head(m).cwiseAbs().maxCoeff() : 0.0) + 1e-300;
  return rmax / scale;
}

}  // namespace saltus
