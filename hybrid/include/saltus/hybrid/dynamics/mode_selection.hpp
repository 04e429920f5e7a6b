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
/// SelectionUniqueness):
/// - Persistent (the default): the contacts' current mode, select()'s `current` argument (compared
///   on the candidate contacts), when it is one of the first max_kept solutions; else the solver's. This is the indicator rule of event-driven
///   schemes (Pfeiffer & Glocker, Multibody Dynamics with Unilateral Contacts, 1996, ch. 6): a
///   closed contact stays closed while its normal force is not negative and its stick while its
///   friction is inside the cone. After an impact the current mode is the impact's post-impact
///   mode: a foot that touched down into stick and may either stay or lift off at the
///   acceleration level stays (docs/refinement.md, "Hopper over three holes").
/// - Solver: the pivoting or Coulomb solver's own (in Painleve's indeterminate case it is the
///   lift-off, where Lemke's pivoting ends first).
/// - MostClosed / FewestClosed: the solution with the most or the fewest closed contacts.
/// Without a `current` mode Persistent is Solver. In a simulation the rule is
/// SimulationOptions::selection.ambiguity; Solver there gives the choice made before Persistent
/// existed (CHANGELOG.md).
enum class AmbiguityChoice { Persistent, Solver, MostClosed, FewestClosed };

/// What the last select() found about the uniqueness of its solution: the modes of all solutions
/// of the acceleration-level problem, enumerated over the combinations of the candidates' states
/// (thesis 2.20-2.23). Per contact: open (lambda_n = 0, y_n >= 0) or closed (y_n = 0,
/// lambda_n >= 0); a closed frictionless or already slipping contact (its friction folded into
/// the columns, A.23) has nothing more to choose; a closed planar contact at tangential rest
/// sticks (y_t = 0, |lambda_t| <= mu lambda_n) or slips either way (lambda_t = -s mu lambda_n,
/// s y_t >= 0, s = +-1). Each combination is a square linear system in its unknown forces;
/// degenerate combinations are skipped (their solutions belong to a neighbouring one). Checked
/// where the problem has at most 12 rows, at most 4096 combinations and no spatial contact at
/// tangential rest (a spatial stick-slip has a continuum of slip directions), and where at least
/// one combination is feasible within the zero bands; otherwise checked = false.
/// Solutions count as distinct when their modes differ (redundant contacts have many force
/// distributions for one mode: not an ambiguity of the mode). A P-matrix problem without friction
/// has exactly one; friction (a slipping contact folded into the columns, Painleve; a coupled
/// Delassus matrix at tangential rest) can give none, two, or more.
template <int NC>
struct SelectionUniqueness {
  static constexpr int max_kept = 4;
  bool checked = false;
  int solutions = 1;  ///< solutions with distinct modes found (1 when not checked)
  /// The index in `modes` of the mode select() returned; 0 also when it returned the solver's mode
  /// and that mode is not among `modes` (beyond max_kept, or outside the enumeration's zero bands).
  int taken = 0;
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
  AmbiguityChoice ambiguity = AmbiguityChoice::Persistent;
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
  /// slip stops). `current`, when given, is the contacts' mode before the selection, which
  /// AmbiguityChoice::Persistent keeps when it is one of several solutions. Throws
  /// ContactProblemFailure when the acceleration-level problem has no solution (Painleve's
  /// paradox: friction too large for the configuration).
  Mode<nc> select(const VecT<double, nx>& x, const VecT<double, nu>& u, const std::array<bool, nc>& candidates,
                  const std::array<bool, nc>& rest = {}, const Mode<nc>* current = nullptr);

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
  // The last problem's layout: the problem index of each contact (-1: not a candidate) and the
  // slip direction of a contact already slipping; the zero bands of forces and accelerations.
  std::array<int, nc> index_{};
  std::array<Eigen::Vector2d, nc> slip_dir_{};
  double force_tolerance_ = 0.0, acceleration_tolerance_ = 0.0;

  using Vector = typename Problem::Vector;
  void assemble(const VecT<double, nx>& x, const VecT<double, nu>& u, const std::array<bool, nc>& candidates,
                const std::array<bool, nc>& rest);
  Mode<nc> mode_of(const Vector& lambda, const Vector& y) const;
  /// Enumerates the solutions (SelectionUniqueness) and puts the one AmbiguityChoice takes into
  /// solution_.
  void enumerate_solutions(const Mode<nc>* current, const std::array<bool, nc>& candidates);
  /// Solves one combination of contact states (per problem contact: 0 open, 1 closed or stick,
  /// 2 slip +, 3 slip -); false when degenerate or infeasible.
  bool solve_combination(const std::array<int, contact_bound(nc)>& state, Vector& lambda, Vector& y) const;
};

}  // namespace saltus
