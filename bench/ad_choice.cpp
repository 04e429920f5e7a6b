// Why Saltus differentiates its scenes with its own dual number (saltus::ad::Dual): the cost of
// a gradient of the SAME templated scene functions with each forward-mode scalar type, and of the
// second-order quantity the library actually needs.
//
// First order (value + gradient), each scene function called unchanged with the scalar type T:
//   hopper_gap         Hopper::gap<T>(0, q)          foot height, nq = 4
//   hopper_mass        Hopper::mass_matrix<T>(q)     all 16 entries with their gradients, nq = 4
//   spatial_box_gap    SpatialBox::gap<T>(0, q)      height of corner 0, nq = 6
// with T = double (the value alone, the floor), saltus::ad::Dual<double, N>,
// Eigen::AutoDiffScalar<Eigen::Matrix<double, N, 1>> (fixed size),
// Eigen::AutoDiffScalar<Eigen::VectorXd> (dynamic size, heap-allocated derivatives) and, when
// ceres/jet.h is installed (libceres-dev, header only, SALTUS_HAVE_CERES_JET), ceres::Jet<double, N>.
//
// Second order (curvature_*): h_n, w_n = dh_n/dq, zeta_n = w_n^T v and kappa_n = v^T (d^2 h_n/dq^2) v
// in one pass, seeded as saltus::evaluate_contact does (hybrid/include/saltus/hybrid/kinematics.hpp):
// inner level along the nq coordinates, outer level along q(s) = q + s v.
//   - saltus: Dual<Dual<double, nq>, 1>.
//   - Eigen::AutoDiffScalar nests (AutoDiffScalar<Matrix<AutoDiffScalar<...>, 1, 1>>, fixed or
//     dynamic) and evaluates the scene code, double constants included, to the same values, so it
//     is benchmarked here too. What it cannot do nested is go through Eigen's decompositions: LLT,
//     PartialPivLU, ColPivHouseholderQR and CompleteOrthogonalDecomposition of a nested
//     AutoDiffScalar matrix do not compile (Eigen 3.4; at one level all four compile).
//   - ceres::Jet<ceres::Jet<double, nq>, 1> cannot run the scene code at all: Jet's mixed
//     operators take the next-lower level only (`0.2 * x` with a double and a nested Jet has no
//     operator, and a nested Jet has no constructor from double). It nests only if every double
//     constant is lifted by hand to the inner Jet, which is not how scene code is written; so
//     there is no Jet curvature benchmark. (Checked with Ceres 2.1 and Eigen 3.4, see README.md.)
//
// Before any timing, every scalar type's result is checked against saltus::ad::Dual (first order)
// and against saltus::evaluate_contact (second order) on all sampled configurations: the values
// must agree to 1e-14 (relative to max(1, |value|)), or the program aborts.
#include "scenes/hopper.hpp"
#include "scenes/spatial_box.hpp"

#include <saltus/ad/dual.hpp>
#include <saltus/hybrid/kinematics.hpp>

#include <benchmark/benchmark.h>
#include <unsupported/Eigen/AutoDiff>
#ifdef SALTUS_HAVE_CERES_JET
#include <ceres/jet.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

namespace {

using saltus::MatT;
using saltus::Vec;
using saltus::VecT;
namespace scenes = saltus::scenes;

// ---- the scalar types: seed q_k along direction k, read the value and the k-th derivative -------

template <int N>
struct PlainDouble {
  using T = double;
  static constexpr const char* name = "double (value only)";
  static T seed(double x, int) { return x; }
  static double value(const T& t) { return t; }
  static double derivative(const T&, int) { return 0.0; }
};

template <int N>
struct SaltusDual {
  using T = saltus::ad::Dual<double, N>;
  static constexpr const char* name = "saltus::ad::Dual";
  static T seed(double x, int k) { return T(x, k); }
  static double value(const T& t) { return t.a; }
  static double derivative(const T& t, int k) { return t.v[k]; }
};

template <int N>
struct EigenFixed {
  using T = Eigen::AutoDiffScalar<Eigen::Matrix<double, N, 1>>;
  static constexpr const char* name = "Eigen::AutoDiffScalar<fixed>";
  static T seed(double x, int k) { return T(x, N, k); }
  static double value(const T& t) { return t.value(); }
  static double derivative(const T& t, int k) { return t.derivatives()[k]; }
};

template <int N>
struct EigenDynamic {
  using T = Eigen::AutoDiffScalar<Eigen::VectorXd>;
  static constexpr const char* name = "Eigen::AutoDiffScalar<VectorXd>";
  static T seed(double x, int k) { return T(x, N, k); }
  static double value(const T& t) { return t.value(); }
  // A constant (T(0), T(mass)) carries an empty derivative vector: its derivatives are zero.
  static double derivative(const T& t, int k) { return k < t.derivatives().size() ? t.derivatives()[k] : 0.0; }
};

#ifdef SALTUS_HAVE_CERES_JET
template <int N>
struct CeresJet {
  using T = ceres::Jet<double, N>;
  static constexpr const char* name = "ceres::Jet";
  static T seed(double x, int k) { return T(x, k); }
  static double value(const T& t) { return t.a; }
  static double derivative(const T& t, int k) { return t.v[k]; }
};
#endif

// ---- the scene functions, called unchanged -----------------------------------------------------

struct HopperGap {
  static constexpr int n = 4, outputs = 1;
  static constexpr const char* name = "hopper_gap";
  scenes::Hopper scene = scenes::Hopper();
  template <class T>
  T gap(const VecT<T, n>& q) const {
    return scene.template gap<T>(0, q);
  }
  template <class T>
  void eval(const VecT<T, n>& q, std::array<T, outputs>& y) const {
    y[0] = gap(q);
  }
};

struct HopperMass {
  static constexpr int n = 4, outputs = n * n;
  static constexpr const char* name = "hopper_mass";
  scenes::Hopper scene = scenes::Hopper();
  template <class T>
  void eval(const VecT<T, n>& q, std::array<T, outputs>& y) const {
    const MatT<T, n, n> M = scene.template mass_matrix<T>(q);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) y[i + n * j] = M(i, j);
  }
};

struct SpatialBoxGap {
  static constexpr int n = 6, outputs = 1;
  static constexpr const char* name = "spatial_box_gap";
  static constexpr int corner = 0;
  scenes::SpatialBox scene = scenes::SpatialBox();
  template <class T>
  T gap(const VecT<T, n>& q) const {
    return scene.template gap<T>(corner, q);
  }
  template <class T>
  void eval(const VecT<T, n>& q, std::array<T, outputs>& y) const {
    y[0] = gap(q);
  }
};

/// out = (value, d/dq_0, ..., d/dq_{n-1}) of every output, with the scalar family A.
template <template <int> class A, class P>
void gradient(const P& p, const Vec<P::n>& q, double* out) {
  constexpr int n = P::n;
  using Ad = A<n>;
  using T = typename Ad::T;
  VecT<T, n> qs;
  for (int k = 0; k < n; ++k) qs[k] = Ad::seed(q[k], k);
  std::array<T, P::outputs> y;
  p.eval(qs, y);
  for (int o = 0; o < P::outputs; ++o) {
    out[o * (n + 1)] = Ad::value(y[o]);
    for (int k = 0; k < n; ++k) out[o * (n + 1) + 1 + k] = Ad::derivative(y[o], k);
  }
}

// ---- second order: (h, w, zeta, kappa) = out[0], out[1..n], out[n+1], out[n+2] -------------------

struct SaltusNested {
  static constexpr const char* name = "saltus::ad::Dual<Dual<double,nq>,1>";
  template <class P>
  static void curvature(const P& p, const Vec<P::n>& q, const Vec<P::n>& v, double* out) {
    constexpr int n = P::n;
    using Inner = saltus::ad::Dual<double, n>;
    using Outer = saltus::ad::Dual<Inner, 1>;
    VecT<Outer, n> qs;
    for (int k = 0; k < n; ++k) qs[k] = Outer(Inner(q[k], k), typename Outer::Gradient(Inner(v[k])));
    const Outer g = p.gap(qs);
    out[0] = g.a.a;
    for (int k = 0; k < n; ++k) out[1 + k] = g.a.v[k];
    out[n + 1] = g.v[0].a;
    out[n + 2] = g.v[0].v.dot(v);
  }
};

struct EigenFixedNested {
  static constexpr const char* name = "Eigen::AutoDiffScalar<fixed> nested";
  template <class P>
  static void curvature(const P& p, const Vec<P::n>& q, const Vec<P::n>& v, double* out) {
    constexpr int n = P::n;
    using Inner = Eigen::AutoDiffScalar<Eigen::Matrix<double, n, 1>>;
    using Outer = Eigen::AutoDiffScalar<Eigen::Matrix<Inner, 1, 1>>;
    VecT<Outer, n> qs;
    for (int k = 0; k < n; ++k) qs[k] = Outer(Inner(q[k], n, k), Eigen::Matrix<Inner, 1, 1>(Inner(v[k])));
    const Outer g = p.gap(qs);
    out[0] = g.value().value();
    for (int k = 0; k < n; ++k) out[1 + k] = g.value().derivatives()[k];
    out[n + 1] = g.derivatives()[0].value();
    out[n + 2] = g.derivatives()[0].derivatives().dot(v);
  }
};

struct EigenDynamicNested {
  static constexpr const char* name = "Eigen::AutoDiffScalar<VectorXd> nested";
  template <class P>
  static void curvature(const P& p, const Vec<P::n>& q, const Vec<P::n>& v, double* out) {
    constexpr int n = P::n;
    using Inner = Eigen::AutoDiffScalar<Eigen::VectorXd>;
    using Outer = Eigen::AutoDiffScalar<Eigen::Matrix<Inner, Eigen::Dynamic, 1>>;
    VecT<Outer, n> qs;
    Eigen::Matrix<Inner, Eigen::Dynamic, 1> dv(1);
    for (int k = 0; k < n; ++k) {
      dv[0] = Inner(v[k], Eigen::VectorXd::Zero(n));
      qs[k] = Outer(Inner(q[k], n, k), dv);
    }
    const Outer g = p.gap(qs);
    out[0] = g.value().value();
    for (int k = 0; k < n; ++k) out[1 + k] = g.value().derivatives()[k];
    out[n + 1] = g.derivatives()[0].value();
    out[n + 2] = g.derivatives()[0].derivatives().dot(v);
  }
};

// ---- sampled states ------------------------------------------------------------------------------

constexpr int kStates = 256;  // cycled through so that nothing is constant-folded

template <int N>
struct States {
  std::vector<Vec<N>> q, v;
};

States<4> hopper_states() {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> x(-1, 1), z(0.2, 0.5), hip(-0.8, 0.8), knee(-1.4, 1.4), vel(-2, 2);
  States<4> s;
  for (int i = 0; i < kStates; ++i) {
    s.q.emplace_back(x(rng), z(rng), hip(rng), knee(rng));
    s.v.emplace_back(vel(rng), vel(rng), vel(rng), vel(rng));
  }
  return s;
}

States<6> box_states() {
  std::mt19937 rng(2025);
  std::uniform_real_distribution<double> pos(-1, 1), ang(-0.6, 0.6), yaw(-3, 3), vel(-2, 2);
  States<6> s;
  for (int i = 0; i < kStates; ++i) {
    Vec<6> q, v;
    q << pos(rng), pos(rng), 0.3 + pos(rng), ang(rng), ang(rng), yaw(rng);
    for (int k = 0; k < 6; ++k) v[k] = vel(rng);
    s.q.push_back(q);
    s.v.push_back(v);
  }
  return s;
}

const States<4>& hopper() {
  static const States<4> s = hopper_states();
  return s;
}
const States<6>& box() {
  static const States<6> s = box_states();
  return s;
}
template <class P>
const auto& states_for() {
  if constexpr (P::n == 4)
    return hopper();
  else
    return box();
}

// ---- the agreement check --------------------------------------------------------------------------

constexpr double kAgreement = 1e-14;
double worst_disagreement = 0.0;

[[noreturn]] void disagree(const std::string& what, int state, int entry, double value, double reference) {
  std::fprintf(stderr, "ad_choice: %s disagrees at state %d, entry %d: %.17g vs %.17g (tolerance %.0e)\n",
               what.c_str(), state, entry, value, reference, kAgreement);
  std::abort();
}

void compare(const std::string& what, int state, const double* value, const double* reference, int count) {
  for (int e = 0; e < count; ++e) {
    const double err = std::abs(value[e] - reference[e]) / std::max(1.0, std::abs(reference[e]));
    worst_disagreement = std::max(worst_disagreement, err);
    if (!(err <= kAgreement)) disagree(what, state, e, value[e], reference[e]);
  }
}

template <template <int> class A, class P>
void check_gradient(const P& p) {
  constexpr int count = P::outputs * (P::n + 1);
  const auto& s = states_for<P>();
  std::array<double, count> ref{}, got{};
  for (int i = 0; i < kStates; ++i) {
    gradient<SaltusDual>(p, s.q[i], ref.data());
    gradient<A>(p, s.q[i], got.data());
    compare(std::string(P::name) + " / " + A<P::n>::name, i, got.data(), ref.data(), count);
  }
}

template <class A, class P, class Scene>
void check_curvature(const P& p, const Scene& scene, int contact) {
  constexpr int n = P::n;
  const auto& s = states_for<P>();
  std::array<double, n + 3> ref{}, got{};
  saltus::ContactKinematics<Scene> ck;
  for (int i = 0; i < kStates; ++i) {
    saltus::evaluate_contact(scene, contact, s.q[i], s.v[i], ck);
    ref[0] = ck.gap;
    for (int k = 0; k < n; ++k) ref[1 + k] = ck.wn[k];
    ref[n + 1] = ck.zeta_n;
    ref[n + 2] = ck.kappa_n;
    A::curvature(p, s.q[i], s.v[i], got.data());
    compare(std::string("curvature ") + P::name + " / " + A::name, i, got.data(), ref.data(), n + 3);
  }
}

// ---- the benchmarks -------------------------------------------------------------------------------

template <template <int> class A, class P>
void register_gradient(const P& p) {
  const std::string name = std::string(P::name) + "/" + A<P::n>::name;
  benchmark::RegisterBenchmark(name.c_str(), [p](benchmark::State& state) {
    const auto& s = states_for<P>();
    std::array<double, P::outputs*(P::n + 1)> out{};
    int i = 0;
    for (auto _ : state) {
      gradient<A>(p, s.q[i], out.data());
      benchmark::DoNotOptimize(out.data());
      benchmark::ClobberMemory();
      i = (i + 1) % kStates;
    }
  });
}

template <class A, class P>
void register_curvature(const P& p) {
  const std::string name = std::string("curvature_") + P::name + "/" + A::name;
  benchmark::RegisterBenchmark(name.c_str(), [p](benchmark::State& state) {
    const auto& s = states_for<P>();
    std::array<double, P::n + 3> out{};
    int i = 0;
    for (auto _ : state) {
      A::curvature(p, s.q[i], s.v[i], out.data());
      benchmark::DoNotOptimize(out.data());
      benchmark::ClobberMemory();
      i = (i + 1) % kStates;
    }
  });
}

template <class P>
void first_order(const P& p) {
  check_gradient<EigenFixed>(p);
  check_gradient<EigenDynamic>(p);
#ifdef SALTUS_HAVE_CERES_JET
  check_gradient<CeresJet>(p);
#endif
  register_gradient<PlainDouble>(p);
  register_gradient<SaltusDual>(p);
  register_gradient<EigenFixed>(p);
  register_gradient<EigenDynamic>(p);
#ifdef SALTUS_HAVE_CERES_JET
  register_gradient<CeresJet>(p);
#endif
}

template <class P, class Scene>
void second_order(const P& p, const Scene& scene, int contact) {
  check_curvature<SaltusNested>(p, scene, contact);
  check_curvature<EigenFixedNested>(p, scene, contact);
  check_curvature<EigenDynamicNested>(p, scene, contact);
  register_curvature<SaltusNested>(p);
  register_curvature<EigenFixedNested>(p);
  register_curvature<EigenDynamicNested>(p);
}

}  // namespace

int main(int argc, char** argv) {
  const HopperGap hopper_gap{};
  const HopperMass hopper_mass{};
  const SpatialBoxGap box_gap{};
  first_order(hopper_gap);
  first_order(hopper_mass);
  first_order(box_gap);
  second_order(hopper_gap, hopper_gap.scene, 0);
  second_order(box_gap, box_gap.scene, SpatialBoxGap::corner);
  std::fprintf(stderr, "ad_choice: all scalar types agree (largest relative difference %.1e <= %.0e over %d states)%s\n",
              worst_disagreement, kAgreement, kStates,
#ifdef SALTUS_HAVE_CERES_JET
              ""
#else
              "; ceres/jet.h not found, ceres::Jet left out"
#endif
  );
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
