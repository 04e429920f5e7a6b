// Everything the dynamics needs at one state (q, v), for any scalar type T (double, or a dual
// number when a derivative of the flow, a guard or a jump map is wanted):
//   M(q) and its Cholesky factor, h(q, v), S(q), and for each contact
//   h_n, w_n = dh_n/dq, zeta_n = w_n^T v, kappa_n = v^T (d^2 h_n/dq^2) v = (d/dt w_n)^T v,
//   W_t = d(tangent position)/dq, zeta_t = W_t^T v, kappa_t = (d/dt W_t)^T v   (thesis 2.1-2.2,
//   2.41, A.22, A.29-A.30).
// The contact quantities come from one forward pass with a nested dual number: the configuration
// is seeded along the nq coordinate directions (inner level) and moved along the velocity
// (outer level, q(s) = q + s v), so the value gives h_n, the inner gradient w_n, the outer
// derivative zeta_n, and the inner gradient of the outer derivative H v, whence kappa_n = v^T H v.
// When T is itself a dual number (derivatives.hpp) the scene code runs three levels deep,
// ad::Dual<ad::Dual<T, nq>, 1> (saltus/ad/autodiff.hpp says why that needs its constructors).
//
// Compiled once per scene: the definitions are in kinematics.hxx, instantiated for T = double
// and T = StateInputDual<S> by SALTUS_INSTANTIATE_SCENE (saltus/hybrid/instantiate.hxx).
#pragma once

#include <saltus/ad/autodiff.hpp>
#include <saltus/hybrid/contact/linear_solve.hpp>
#include <saltus/hybrid/vocabulary/scene.hpp>

#include <Eigen/Cholesky>

#include <array>

namespace saltus {

template <Scene S, class T = double>
struct ContactKinematics {
  static constexpr int nq = S::nq;
  T gap{};                     ///< h_n(q)
  VecT<T, nq> wn;              ///< w_n = dh_n/dq
  T zeta_n{};                  ///< normal velocity w_n^T v
  T kappa_n{};                 ///< curvature term (d/dt w_n)^T v
  MatT<T, nq, 2> Wt;           ///< tangent Jacobian columns (first `tangents` used)
  VecT<T, 2> zeta_t;           ///< tangential velocity W_t^T v
  VecT<T, 2> kappa_t;          ///< (d/dt W_t)^T v
  int tangents = 0;

  ContactKinematics() {
    wn.setZero();
    Wt.setZero();
    zeta_t.setZero();
    kappa_t.setZero();
  }
};

/// Fills `out` for contact i at (q, v); allocation-free.
template <Scene S, class T>
void evaluate_contact(const S& scene, int i, const VecT<T, S::nq>& q, const VecT<T, S::nq>& v,
                      ContactKinematics<S, T>& out);

/// M, the Cholesky factor of its value, h, S and all contacts at (q, v).
template <Scene S, class T = double>
struct Kinematics {
  static constexpr int nq = S::nq, nu = S::nu, nc = S::nc;
  MatT<T, nq, nq> M;
  Eigen::LLT<Mat<nq, nq>> llt;  ///< of value(M): M^{-1} for any T via linear_solve.hpp
  VecT<T, nq> h;
  MatT<T, nq, nu> S_u;  ///< input matrix S(q)
  std::array<ContactKinematics<S, T>, nc> contacts;

  /// out = M^{-1} rhs, column by column, for rhs with scalars T.
  template <class Rhs, class Out>
  void solve_mass(const Rhs& rhs, Out& out) const {
    VecT<T, nq> x, work, b;
    auto solve_double = [this](auto& v) { llt.solveInPlace(v); };
    out.resize(nq, rhs.cols());
    for (Eigen::Index j = 0; j < rhs.cols(); ++j) {
      b = rhs.col(j);
      solve_with_value_factorization(M, b, solve_double, x, work);
      out.col(j) = x;
    }
  }
};

/// Evaluates M (and factorises it), h and S. Throws NonSpdMassMatrix if M is not SPD.
template <Scene S, class T>
void evaluate_dynamics(const S& scene, const VecT<T, S::nq>& q, const VecT<T, S::nq>& v,
                       Kinematics<S, T>& k);

/// evaluate_dynamics plus every contact.
template <Scene S, class T>
void evaluate_kinematics(const S& scene, const VecT<T, S::nq>& q, const VecT<T, S::nq>& v,
                         Kinematics<S, T>& k);

/// Kinetic energy 1/2 v^T M v.
template <class T, int N>
T kinetic_energy(const MatT<T, N, N>& M, const VecT<T, N>& v) {
  return T(0.5) * v.dot(M * v);
}

/// The velocity-dependent part of h that follows from M alone (Christoffel symbols):
///   c(q, v) = (dM/dt) v - 1/2 d(v^T M v)/dq,
/// i.e. the Coriolis and centrifugal terms of the Lagrangian L = 1/2 v^T M(q) v. Scenes whose mass
/// matrix is configuration dependent add it to their bias; derived by one dual pass over M.
template <Scene S, class T>
VecT<T, S::nq> coriolis_from_mass_matrix(const S& scene, const VecT<T, S::nq>& q,
                                         const VecT<T, S::nq>& v) {
  constexpr int nq = S::nq;
  using D = ad::Dual<T, nq>;
  VecT<D, nq> qd;
  for (int k = 0; k < nq; ++k) qd[k] = ad::seed<nq>(q[k], k);
  const MatT<D, nq, nq> Md = scene.template mass_matrix<D>(qd);
  VecT<T, nq> c = VecT<T, nq>::Zero();
  for (int i = 0; i < nq; ++i)
    for (int j = 0; j < nq; ++j)
      for (int k = 0; k < nq; ++k) {
        // (dM_ij/dq_k v_k) v_j - 1/2 (dM_jk/dq_i) v_j v_k
        c[i] += Md(i, j).derivatives()[k] * v[k] * v[j] - T(0.5) * Md(j, k).derivatives()[i] * v[j] * v[k];
      }
  return c;
}

}  // namespace saltus
