// The constraints a contact mode keeps, and the projection onto them in the kinetic metric, the
// one place where a state is brought back onto its mode (CVODE's projection, the numerical twin's
// perturbed starts, the tests' consistent states).
//
// In mode m, a closed contact keeps its gap h_n(q) and its normal velocity w_n^T v, and a sticking
// contact also its tangential velocity W_t^T v (thesis 2.33-2.41). The constraint values are
//     c(x) = (c_q(q), c_v(q, v)),  c_q = (h_n of each closed contact),
//                                  c_v = (w_n^T v of each closed contact, W_t^T v of each sticking one)
// in contact order (c_v in the Delassus assembly's row order, delassus.hpp). The projection onto
// {c(x) = c*} corrects the configuration first, then the velocity at the corrected configuration,
// each by the smallest change in the kinetic metric (the M^{-1} metric on forces):
//     q <- q - M^{-1} G^T (G M^{-1} G^T)^+ (c_q(q) - c_q*),  G = dc_q/dq (rows w_n^T),
//          repeated (Gauss-Newton) until the step is at round-off, at most `max_iterations` times;
//     v <- v - M^{-1} J^T (J M^{-1} J^T)^+ (J v - c_v*),     J = dc_v/dv at the new q,
// which for the velocity is exact (c_v is linear in v) and is the impact law's own projection
// (a frictionless plastic impulse that makes the constrained velocities c_v*). The pseudo-inverse
// takes redundant contacts (a box flat on four corners). An error vector, if given, is projected
// with the same linear operators (CVODE projects its local error estimate so).
// Definitions in constraints.hxx (compiled once per scene, saltus/hybrid/instantiate.hpp).
#pragma once

#include <saltus/hybrid/contact/linear_solve.hpp>
#include <saltus/hybrid/dynamics/delassus.hpp>
#include <saltus/hybrid/dynamics/kinematics.hpp>
#include <saltus/hybrid/vocabulary/mode.hpp>

namespace saltus {

template <Scene S>
class ConstraintProjection {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nc = S::nc;
  static constexpr int max_rows = DelassusAssembly<S>::max_rows;
  using State = VecT<double, nx>;
  /// c_q (at most nc values) and c_v (at most 3 nc), sized by the mode.
  using Values = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, max_rows, 1>;

  int max_iterations = 4;  ///< Gauss-Newton steps on the configuration

  /// c_q(q) and c_v(q, v) of `mode` at x (file comment). Allocation-free.
  void values(const S& scene, const Mode<nc>& mode, const State& x, Values& c_q, Values& c_v);

  /// Projects x onto {c_q = c_q*, c_v = c_v*} (zero targets when null: the mode's own manifold),
  /// and `error`, if non-null, with the linearised operators. Targets must have the sizes values()
  /// gives for this mode. Allocation-free. @throws NonSpdMassMatrix
  void project(const S& scene, const Mode<nc>& mode, State& x, const Values* c_q_target = nullptr,
               const Values* c_v_target = nullptr, State* error = nullptr);

 private:
  // d = M^{-1} G^T (G M^{-1} G^T)^+ b over the assembled rows (kinematics in kin_).
  void kinetic_step(const Values& b, VecT<double, nq>& d);
  void assemble(const S& scene, const Mode<nc>& mode, bool velocity_rows);

  Kinematics<S> kin_;
  DelassusAssembly<S> assembly_;
  MinNormSolver<max_rows> solver_;
  typename MinNormSolver<max_rows>::Vector multiplier_;
  Values residual_, c_q_, c_v_;
  std::array<VecT<double, 2>, nc> no_slip_{};
};

}  // namespace saltus
