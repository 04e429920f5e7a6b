// The impact problem (thesis 2.27-2.32): the post-impact velocity, the impulses and the
// post-impact mode of every contact, for any set of impacting and already-closed contacts,
// with Newton-type restitution (2.10, and tangential restitution: impact_law.hpp, energy-consistent
// by default) and Coulomb's law on the impulses (2.29-2.30).
//
// In Delassus form, with W stacking w_n^T and W_t^T of the contacts at the impact and
// y = xi = W v+ + (e_n min(w_n^T v-, 0), e_t W_t^T v-) (the impact law's velocity):
//     y = (W M^{-1} W^T) Lambda + W v- + (e_n min(w_n^T v-, 0), e_t W_t^T v-)
// and the Signorini-Coulomb conditions on (y, Lambda) of contact_problem.hpp.
//  - All contacts planar or frictionless: the exact LCP of lemke.hpp (finite, exact up to
//    round-off; Lemke processes this LCP, Anitescu & Potra 1997). Complete enumeration would cost
//    4^nc linear solves and is kept for the tests only.
//  - Any spatial contact: the semismooth Newton method on the Alart-Curnier natural map of
//    coulomb_solver.hpp, with its certified residual.
// The solution fixes the impulse mode (who takes an impulse, sticking or slipping along which
// post-impact direction); the jump map of that mode (jump_map.hpp) then recomputes v+ and the
// minimum-norm impulse, so that the value and the derivative used by the jump gains are those of
// one and the same map. Redundant contacts (a box landing flat, or three points along one edge)
// give a singular Delassus matrix (`singular_delassus`: the matrix of every contact in the
// problem, normal and tangential rows): the impulses are not unique. Whether v+ is: fix the
// impulse mode (who takes an impulse, the slip directions d_i); contact i's impulse is
// lambda_i f_i, f_i = w_n,i - mu W_t,i d_i for a slipping contact, and the impacting contacts need
// A lambda = -J_n v- (e = 0), A = J_n M^-1 F. rank A <= rank J_n < n_c for redundant contacts
// (four coplanar corners: rank 3), so A has a null vector k and lambda + s k (small s, lambda > 0)
// meets the same normal conditions, with v+ changed by s M^-1 F k: v+ is unique only if F k = 0.
// Coplanar contacts with common normal n slipping along ONE direction d: the spread k of
// null(J_n^T) (sum k_i = 0, sum k_i rho_i = 0, r_i = rho_i + h n from the centre of mass) carries
// the friction wrench -mu (sum k_i d, sum k_i r_i x d) = 0, so F k = 0 and, when A has rank
// rank J_n (generically; a large mu can lower it, Painleve-like), null(A) is that k: v+ unique.
// Slipping along DIFFERENT directions (a box landing flat while it turns, or inside the cascade of
// a perturbed flat landing) the null vector of A is another k' with F k' != 0 (checked
// numerically: a 0.4 x 0.2 box, h = 0.05, mu = 0.5, four distinct directions): for the mode's directions v+ is not unique; with the directions tied to
// v+ uniqueness is not shown either way, and the returned v+ is Saltus' selection, not the model's
// answer (the jump gains refuse such impacts when their differentiated jump map does not
// reproduce it: JumpGainOptions::jump_map_tolerance; seen on the spatial box, v+ differing by
// 1.4e-5-3.3e-5). The impulse returned is then the minimum-Euclidean-norm impulse WITHIN the
// identified impulse mode (the contacts the solver gave an impulse, their stick/slip roles and
// slip directions; equal shares for a symmetric box) whenever it satisfies the contact laws, and
// `minimum_norm_impulse` says so; otherwise the solver's own impulse is returned and the flag
// is false. It is not the minimum-norm impulse over all admissible splits: the solver may give
// a redundant contact no impulse at all (three collinear points: 0 / 0.891 / 0.099 of the total
// is a valid answer), and the mode it identifies fixes the split. A caller who needs a
// particular split among the admissible ones must choose it with their own criterion.
#pragma once

#include <saltus/hybrid/contact/contact_problem.hpp>
#include <saltus/hybrid/contact/coulomb_solver.hpp>
#include <saltus/hybrid/dynamics/impact_law.hpp>
#include <saltus/hybrid/dynamics/jump_map.hpp>
#include <saltus/hybrid/contact/lemke.hpp>

#include <array>
#include <string>

namespace saltus {

struct ImpactOptions {
  /// Contacts whose gap is at most this (m, or the scene's length unit) take part in the impact.
  double gap_tolerance = 1e-9;
  /// A post-impact contact velocity below velocity_tolerance * (velocity scale) counts as zero.
  double velocity_tolerance = 1e-9;
  /// A normal impulse below impulse_tolerance * (impulse scale) counts as no impulse.
  double impulse_tolerance = 1e-11;
  /// Largest accepted natural-map residual of the contact problem (relative).
  double residual_tolerance = 1e-10;
  enum class Solver { Automatic, Lemke, Coulomb };
  Solver solver = Solver::Automatic;
  /// Options of the semismooth Newton solver used for spatial friction.
  CoulombSolverOptions coulomb{};
};

template <Scene S>
struct ImpactResult {
  static constexpr int nx = 2 * S::nq, nc = S::nc;
  VecT<double, nx> x_plus;
  ImpactMode<nc> impulse_mode;  ///< who takes an impulse, and how
  ImpactCoefficients<nc> coefficients;  ///< restitution of this impact (impact_law.hpp)
  Mode<nc> post_mode;           ///< velocity level: open if separating, else stick / slip
  std::array<bool, nc> in_problem{};
  std::array<ContactForce<double>, nc> impulse{};
  std::array<double, nc> normal_velocity_minus{}, normal_velocity_plus{};
  std::array<Eigen::Vector2d, nc> tangent_velocity_plus{};  ///< zeta_t^+ (physical, not xi_t)
  double kinetic_energy_minus = 0.0, kinetic_energy_plus = 0.0;
  double residual = 0.0;            ///< natural-map residual of the contact problem (relative)
  double signorini_residual = 0.0;  ///< of the returned (y, Lambda), relative (see below)
  double coulomb_residual = 0.0;
  double velocity_scale = 0.0, impulse_scale = 0.0;
  int iterations = 0;
  bool used_lemke = false;
  /// The impulse is the minimum-norm one among the impulses of the identified impulse mode
  /// (see the file comment: not the minimum over all admissible splits).
  bool minimum_norm_impulse = false;
  /// The Delassus matrix of every contact in the impact problem (normal and tangential rows) is
  /// rank deficient: redundant contacts, the impulse split is not unique (the velocity is unless
  /// redundant contacts slip along different directions: file comment).
  bool singular_delassus = false;
};

template <Scene S>
class ImpactSolver {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nc = S::nc;
  using Problem = ContactProblem<contact_bound(nc)>;
  using Solution = ContactSolution<contact_bound(nc)>;
  using Lemke = LemkeSolver<contact_bound(nc)>;
  using Coulomb = CoulombSolver<contact_bound(nc)>;

  static_assert(S::nc > 0, "an impact needs a scene with contacts");

  explicit ImpactSolver(const S& scene, ImpactOptions options = {});
  ImpactSolver(S&&, ImpactOptions = {}) = delete;  // keeps a reference: would dangle

  const ImpactOptions& options() const { return options_; }

  /// Impact at x- with the contacts whose gap is within gap_tolerance. The returned reference is
  /// the solver's own workspace (so that a solve allocates nothing): the next solve overwrites
  /// it; copy the result (ImpactResult<S> r = solver.solve(x);) to keep it.
  const ImpactResult<S>& solve(const VecT<double, nx>& x_minus);

  /// Impact at x- with an explicit set of contacts taking part; `inelastic[i]` sets e_n = 0 for
  /// contact i in this impact (the simulator's rest criterion). The same reference as above:
  /// overwritten by the next solve.
  const ImpactResult<S>& solve(const VecT<double, nx>& x_minus, const std::array<bool, nc>& in_problem,
                               const std::array<bool, nc>& inelastic = {});

  const ImpactResult<S>& result() const { return result_; }
  /// Restitution coefficients of the last solve (impact_law.hpp: the energy-consistent common
  /// coefficient by default, 0 where made inelastic).
  const ImpactCoefficients<nc>& coefficients() const { return coefficients_; }
  /// The last contact problem, at the solve's working velocity scale (v- scaled by a power of two
  /// to unit scale when max|v-| is outside [2^-32, 2^32]; see impact.hxx).
  const Problem& problem() const { return problem_; }

 private:
  /// Solves at the (possibly scaled) state x_minus; x_reported is the caller's state, for messages.
  void solve_evaluated(const VecT<double, nx>& x_minus, const std::array<bool, nc>& in_problem,
                       const VecT<double, nx>& x_reported);

  /// Copies x- into x_work_ with its velocity scaled by 2^-exponent to unit scale (impact.hxx:
  /// positive homogeneity); returns the exponent, 0 when no scaling is needed.
  int scale_velocity(const VecT<double, nx>& x_minus);
  /// Scales the result of a solve at x_work_ back to the caller's velocity scale.
  void unscale_result(int exponent, const VecT<double, nx>& x_minus);

  void fill_from_jump_map(const VecT<double, nx>& x_minus, const std::array<int, nc>& index);

  void fill_from_solver(const VecT<double, nx>& x_minus, const std::array<int, nc>& index,
                        const VecT<double, nq>& v_plus);

  /// Signorini and Coulomb residuals of the returned (v+, Lambda), relative to the impulse scale
  /// L (the largest impulse component, or V / max|D| if larger: the impulse that changes a
  /// contact velocity by V, below which impulses are round-off of the solve) and the velocity
  /// scale V (largest pre-impact contact velocity):
  ///   Signorini: max(-Lambda_n, 0)/L, max(-y_n, 0)/V, |Lambda_n y_n|/(L V)
  ///   Coulomb:   max(||Lambda_t|| - mu Lambda_n, 0)/L and, where y_t != 0,
  ///              ||Lambda_t + mu Lambda_n y_t/||y_t|| || / L.
  void compute_law_residuals(const VecT<double, nx>& x_minus, const std::array<int, nc>& index);

  const S& scene_;
  ImpactOptions options_;
  Problem problem_;
  Solution solution_;
  Lemke lemke_;
  Coulomb coulomb_;
  JumpWorkspace<S, double> jump_;
  DelassusAssembly<S> assembly_;
  std::array<VecT<double, 2>, nc> no_slip_directions_{};  ///< unused: every contact is Stick
  VecT<double, nx> x_jump_;
  VecT<double, nx> x_work_;  ///< x- with its velocity at unit scale (scale_velocity)
  ImpactCoefficients<nc> coefficients_{};
  MinNormSolver<DelassusAssembly<S>::max_rows> problem_delassus_;  ///< for the rank of the problem
  int problem_rank_ = 0;
  ImpactResult<S> result_;
  double velocity_scale_ = 1.0, impulse_scale_ = 1.0;
};

}  // namespace saltus
