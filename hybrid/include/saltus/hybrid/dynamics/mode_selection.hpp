// Choosing a consistent contact mode at the acceleration level (thesis 2.20-2.23, 2.41, and the
// contact LCP of the time-freezing paper, eqs. 9-12): among the contacts that are closed at the
// velocity level (gap = 0, normal velocity = 0), which stay closed, and of those which stick and
// which slip, given the current state and input. It is the contact problem of
// contact_problem.hpp with accelerations in place of velocities:
//     y = J a + kappa = (J M^{-1} F) lambda + J a_free + kappa,
// Signorini between normal accelerations and forces, Coulomb between tangential accelerations and
// friction forces for contacts at tangential rest. A contact already slipping has its friction
// fixed along -zeta_t/||zeta_t|| (thesis A.23), folded into the columns of J M^{-1} F.
// Used after impacts (an impact into stick that slips at once, thesis B.3), at the stop of a
// slip (stick, or slip on the other way round), and for the initial state.
#pragma once

#include <saltus/hybrid/contact/contact_problem.hpp>
#include <saltus/hybrid/contact/coulomb_solver.hpp>
#include <saltus/hybrid/dynamics/delassus.hpp>
#include <saltus/hybrid/dynamics/flow.hpp>
#include <saltus/hybrid/contact/lemke.hpp>

#include <array>

namespace saltus {

/// Which solution select() takes when the acceleration-level problem has several (see
/// SelectionUniqueness): the solver's (the default, so that a simulation's result does not depend
/// on whether the enumeration ran; in Painleve's indeterminate case it is the lift-off, where
/// Lemke's pivoting ends first), or the one with the most or the fewest closed contacts.
enum class AmbiguityChoice { Solver, MostClosed, FewestClosed };

/// What the last select() found about the uniqueness of its solution. Checked where every
/// candidate contact is frictionless or already slipping: the problem is then a linear
/// complementarity problem in the normal forces alone, y = A lambda + b, whose solutions are
/// enumerated over the 2^m complementary index sets (m <= 12 rows): A_II lambda_I = -b_I,
/// lambda_I >= 0, y_J >= 0. Solutions count as distinct when their modes differ (redundant
/// contacts have many force distributions for one mode: not an ambiguity of the mode). A P-matrix A has exactly one; a non-P A (friction folded into the
/// columns of a slipping contact, Painleve) can have none, two, or more. Problems with a contact
/// at tangential rest (a cone complementarity problem) are not enumerated (checked = false).
template <int NC>
struct SelectionUniqueness {
  static constexpr int max_kept = 4;
  bool checked = false;
  int solutions = 1;  ///< solutions with distinct modes found (1 when not checked)
  int taken = 0;      ///< which of `modes` select() returned
  std::array<Mode<NC>, max_kept> modes{};  ///< the first max_kept solutions' modes
};

struct ModeSelectionOptions {
  /// A contact velocity below velocity_tolerance * max(1, ||v||_inf) counts as zero.
  double velocity_tolerance = 1e-8;
  /// A normal force below force_tolerance * (force scale) counts as zero.
  double force_tolerance = 1e-10;
  /// An acceleration below acceleration_tolerance * (acceleration scale) counts as zero.
  double acceleration_tolerance = 1e-9;
  double residual_tolerance = 1e-9;
  AmbiguityChoice ambiguity = AmbiguityChoice::Solver;
};

template <Scene S>
class ModeSelector {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu, nc = S::nc;
  static constexpr int max_rows = 3 * nc;
  using Problem = ContactProblem<contact_bound(nc)>;
  using Solution = ContactSolution<contact_bound(nc)>;
  using Lemke = LemkeSolver<contact_bound(nc)>;
  using Coulomb = CoulombSolver<contact_bound(nc)>;

  explicit ModeSelector(const S& scene, ModeSelectionOptions options = {}) : scene_(scene), options_(options) {}
  ModeSelector(S&&, ModeSelectionOptions = {}) = delete;  // keeps a reference: would dangle

  /// The mode of the contacts in `candidates` at (x, u); contacts not in it are open.
  /// `rest[i]` marks a candidate whose tangential velocity is to be taken as zero (the instant a
  /// slip stops). Throws ContactProblemFailure when the acceleration-level problem has no solution
  /// (Painleve's paradox: friction too large for the configuration).
  Mode<nc> select(const VecT<double, nx>& x, const VecT<double, nu>& u, const std::array<bool, nc>& candidates,
                  const std::array<bool, nc>& rest = {});

  const Solution& solution() const { return solution_; }
  /// Uniqueness of the last select()'s solution (see SelectionUniqueness).
  const SelectionUniqueness<nc>& uniqueness() const { return uniqueness_; }

 private:
  const S& scene_;
  ModeSelectionOptions options_;
  Kinematics<S> kin_;
  Problem problem_;
  Solution solution_;
  Lemke lemke_;
  Coulomb coulomb_;
  DelassusAssembly<S> assembly_;
  SelectionUniqueness<nc> uniqueness_;

};

}  // namespace saltus
