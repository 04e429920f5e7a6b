// Definitions of kinematics.hpp (see there for the math).
#pragma once

#include <saltus/hybrid/dynamics/kinematics.hpp>

namespace saltus {

template <Scene S, class T>
void evaluate_contact(const S& scene, int i, const VecT<T, S::nq>& q, const VecT<T, S::nq>& v,
                      ContactKinematics<S, T>& out) {
  constexpr int nq = S::nq;
  using Inner = ad::Dual<T, nq>;
  using Outer = ad::Dual<Inner, 1>;
  VecT<Outer, nq> qs;
  for (int k = 0; k < nq; ++k) qs[k] = Outer(ad::seed<nq>(q[k], k), typename Outer::Gradient(Inner(v[k])));

  const Outer g = scene.template gap<Outer>(i, qs);
  out.gap = g.value().value();
  out.wn = g.value().derivatives();
  out.zeta_n = g.derivatives()[0].value();
  out.kappa_n = g.derivatives()[0].derivatives().dot(v);

  const int nt = scene.contact(i).tangents();
  out.tangents = nt;
  if (nt > 0) {
    const VecT<Outer, 2> tp = scene.template tangent_position<Outer>(i, qs);
    // Straight-line code for the (at most two) tangents, not `for (k = 0; k < nt; ++k)`: GCC 12.2
    // at -O3 miscompiled that loop. IVOPTs gave its stores one induction variable iv = &out + 8 k
    // (the stride of zeta_t) and wrote the store to out.Wt.col(k) (stride nq doubles; nq = 4) as
    // MEM[0B + (-3 &out) + 4 iv], a reference with the literal base 0; the modref pass takes that
    // for a null dereference, stops analysing the block there ("NULL memory access; terminating
    // BB" in -fdump-tree-modref2) and publishes a summary in which evaluate_contact
    // never writes W_t, zeta_t or kappa_t, so a caller that trusts it reads back what was there
    // before the call (ContactKinematics' zeros): a central difference of W_t^T v came out exactly
    // 0 in the scene battery. Not undefined behaviour in Saltus (UBSan and ASan builds are silent,
    // -Wall -Wextra -Wstrict-aliasing=1 -Wmaybe-uninitialized too, -fno-strict-aliasing does not
    // cure it; -fno-ipa-modref, -fno-tree-fre or -fno-tree-pre do; clang 14 -O3 is correct). The
    // same null-based references appear elsewhere (at -O2 too), so saltus::hybrid also passes
    // -fno-ipa-modref to GCC >= 12 (hybrid/CMakeLists.txt). Reduced reproducer: tests/test_dual.cpp,
    // GccModrefNullBaseLoop.
    const auto store = [&](int k) {
      out.Wt.col(k) = tp[k].value().derivatives();
      out.zeta_t[k] = tp[k].derivatives()[0].value();
      out.kappa_t[k] = tp[k].derivatives()[0].derivatives().dot(v);
    };
    store(0);
    if (nt > 1) store(1);
  }
}

template <Scene S, class T>
void evaluate_dynamics(const S& scene, const VecT<T, S::nq>& q, const VecT<T, S::nq>& v, Kinematics<S, T>& k) {
  k.M = scene.template mass_matrix<T>(q);
  Mat<S::nq, S::nq> M0;
  ad::value_into(k.M, M0);
  k.llt.compute(M0);
  if (k.llt.info() != Eigen::Success) {
    VecT<double, S::nq> qd;
    for (int i = 0; i < S::nq; ++i) qd[i] = ad::value_of(q[i]);
    throw NonSpdMassMatrix(detail::concat("mass matrix is not symmetric positive definite at q = [", qd.transpose(), "]"));
  }
  k.h = scene.template bias<T>(q, v);
  k.S_u = scene_input_matrix<S, T>(scene, q);
}

template <Scene S, class T>
void evaluate_kinematics(const S& scene, const VecT<T, S::nq>& q, const VecT<T, S::nq>& v, Kinematics<S, T>& k) {
  evaluate_dynamics(scene, q, v, k);
  for (int i = 0; i < S::nc; ++i) evaluate_contact(scene, i, q, v, k.contacts[i]);
}

}  // namespace saltus
