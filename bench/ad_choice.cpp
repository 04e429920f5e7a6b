// Why Saltus differentiates its scenes with Eigen's AutoDiffScalar (saltus::ad::Dual, a thin
// class over Eigen::AutoDiffScalar<Eigen::Matrix<T, N, 1>>, hybrid/include/saltus/ad/autodiff.hpp):
// the cost of a gradient of the SAME templated scene functions with each forward-mode scalar type,
// and of the second- and third-order quantities the library actually needs.
//
// First order (value + gradient), each scene function called unchanged with the scalar type T:
//   hopper_gap         Hopper::gap<T>(0, q)          foot height, nq = 4
//   hopper_mass        Hopper::mass_matrix<T>(q)     all 16 entries with their gradients, nq = 4
//   spatial_box_gap    SpatialBox::gap<T>(0, q)      height of corner 0, nq = 6
// with T = double (the value alone, the floor); former::Dual<double, N>, Saltus' former
// hand-written dual number, kept in this file as the benchmark's BASELINE (it is no longer part of
// the library); saltus::ad::Dual<double, N> (what the library uses);
// Eigen::AutoDiffScalar<Eigen::Matrix<double, N, 1>> as Eigen ships it (fixed size);
// Eigen::AutoDiffScalar<Eigen::VectorXd> (dynamic size, heap-allocated derivatives) and, when
// ceres/jet.h is installed (libceres-dev, header only, SALTUS_HAVE_CERES_JET), ceres::Jet<double, N>.
//
// Second order (curvature_*): h_n, w_n = dh_n/dq, zeta_n = w_n^T v and kappa_n = v^T (d^2 h_n/dq^2) v
// in one pass, seeded as saltus::evaluate_contact does (hybrid/include/saltus/hybrid/dynamics/kinematics.hpp):
// inner level along the nq coordinates, outer level along q(s) = q + s v.
//   - former::Dual<former::Dual<double, nq>, 1> and saltus::ad::Dual<saltus::ad::Dual<double, nq>, 1>.
//   - Eigen::AutoDiffScalar nests (AutoDiffScalar<Matrix<AutoDiffScalar<...>, 1, 1>>, fixed or
//     dynamic) and evaluates the scene code, double constants included, at two levels. What it
//     cannot do nested is go through Eigen's decompositions: LLT, PartialPivLU, ColPivHouseholderQR
//     and CompleteOrthogonalDecomposition of a nested AutoDiffScalar matrix do not compile (Eigen
//     3.4; at one level all four compile). Saltus factorises values only (linear_solve.hpp).
//   - ceres::Jet<ceres::Jet<double, nq>, 1> cannot run the scene code at all: Jet's mixed
//     operators take the next-lower level only (`0.2 * x` with a double and a nested Jet has no
//     operator, and a nested Jet has no constructor from double). It nests only if every double
//     constant is lifted by hand to the inner Jet, which is not how scene code is written; so
//     there is no Jet curvature benchmark. (Checked with Ceres 2.1 and Eigen 3.4, see README.md.)
//
// Third order (curvature_jacobian_*): the same four quantities and their derivatives along the
// 2 nq directions of (q, v), i.e. the contact part of the flow Jacobian (derivatives.hpp), three
// nested levels: Dual<Dual<Dual<double, 2 nq>, nq>, 1>.
//   - former::Dual and saltus::ad::Dual (the latter through saltus::evaluate_contact itself).
//   - Eigen::AutoDiffScalar as shipped does not compile here: at the third level a double
//     constant needs two user-defined conversions (`0.5 * x`, `x < 0.0`, `T(0.5)` and
//     `Matrix<T, 2, 1>::Zero()` all fail), which is why saltus::ad::Dual adds constructors.
//
// Before any timing, every scalar type's result is checked against former::Dual (first and
// third order) and against saltus::evaluate_contact (second order) on all sampled configurations:
// the values must agree to 1e-14 (relative to max(1, |value|)), or the program aborts.
#include "scenes/hopper.hpp"
#include "scenes/spatial_box.hpp"

#include <saltus/ad/autodiff.hpp>
#include <saltus/hybrid/dynamics/kinematics.hxx>

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
#include <limits>
#include <ostream>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

// ---- the baseline: Saltus' former hand-written dual number (library code until the port to ----
// ---- Eigen's AutoDiffScalar), unchanged but for its namespace. Not part of the library. --------

namespace former {

template <class T, int N>
class Dual;

// passive_for<S, D>: S can be used as a constant inside D (a double, an int, or any lower
// nesting level of D).
template <class S, class D>
struct passive_for : std::false_type {};
template <class S, class T, int N>
struct passive_for<S, Dual<T, N>>
    : std::bool_constant<std::is_arithmetic_v<S> || std::is_same_v<S, T> || passive_for<S, T>::value> {};
template <class S, class D>
inline constexpr bool passive_for_v = passive_for<std::remove_cvref_t<S>, D>::value;

/// Innermost real value of a possibly nested dual number.
inline double value_of(double x) { return x; }
template <class T, int N>
double value_of(const Dual<T, N>& x) {
  return value_of(x.a);
}

/// A value a and its derivatives v along N directions: a + sum_k v_k eps_k, eps_j eps_k = 0.
template <class T, int N>
class Dual {
 public:
  static_assert(N > 0, "Dual needs at least one direction");
  using value_type = T;
  using Gradient = Eigen::Matrix<T, N, 1>;
  static constexpr int directions = N;

  T a;
  Gradient v;

  Dual() : a(0), v(Gradient::Zero()) {}
  // Implicit on purpose: constants of any lower level become duals with zero gradient, which is
  // what Eigen's decompositions (Scalar(0), RealScalar(1)) and scene code rely on.
  template <class S>
    requires passive_for_v<S, Dual>
  Dual(const S& value) : a(value), v(Gradient::Zero()) {}  // NOLINT(google-explicit-constructor)
  /// The k-th seed: value x, derivative 1 along direction k.
  Dual(const T& value, int k) : a(value), v(Gradient::Zero()) { v[k] = T(1); }
  Dual(const T& value, const Gradient& gradient) : a(value), v(gradient) {}

  Dual& operator+=(const Dual& y) {
    a += y.a;
    v += y.v;
    return *this;
  }
  Dual& operator-=(const Dual& y) {
    a -= y.a;
    v -= y.v;
    return *this;
  }
  Dual& operator*=(const Dual& y) {
    v = v * y.a + y.v * a;
    a *= y.a;
    return *this;
  }
  Dual& operator/=(const Dual& y) {
    const T inv = T(1) / y.a;
    a *= inv;
    v = (v - a * y.v) * inv;
    return *this;
  }

  // ---- arithmetic, as hidden friends: found by argument-dependent lookup only, which keeps
  // overload resolution (most of the compile time of scene code) small. Constants mix in as
  // double, and for nested duals also as the next lower level T (`Lower`); other constants
  // convert implicitly.
 private:
  struct NotALevel {};
  using Lower = std::conditional_t<std::is_same_v<T, double>, NotALevel, T>;

 public:
  friend Dual operator+(const Dual& x) { return x; }
  friend Dual operator-(const Dual& x) { return Dual(-x.a, -x.v); }
  friend Dual operator+(const Dual& x, const Dual& y) { return Dual(x.a + y.a, x.v + y.v); }
  friend Dual operator-(const Dual& x, const Dual& y) { return Dual(x.a - y.a, x.v - y.v); }
  friend Dual operator*(const Dual& x, const Dual& y) { return Dual(x.a * y.a, x.v * y.a + y.v * x.a); }
  friend Dual operator/(const Dual& x, const Dual& y) {
    const T inv = T(1) / y.a;
    const T q = x.a * inv;
    return Dual(q, (x.v - q * y.v) * inv);
  }
#define SALTUS_DUAL_MIXED(Scalar)                                                               \
  friend Dual operator+(const Dual& x, const Scalar& s) { return Dual(x.a + s, x.v); }          \
  friend Dual operator+(const Scalar& s, const Dual& x) { return Dual(s + x.a, x.v); }          \
  friend Dual operator-(const Dual& x, const Scalar& s) { return Dual(x.a - s, x.v); }          \
  friend Dual operator-(const Scalar& s, const Dual& x) { return Dual(s - x.a, -x.v); }         \
  friend Dual operator*(const Dual& x, const Scalar& s) { return Dual(x.a * s, x.v * T(s)); }   \
  friend Dual operator*(const Scalar& s, const Dual& x) { return Dual(s * x.a, x.v * T(s)); }   \
  friend Dual operator/(const Dual& x, const Scalar& s) {                                       \
    const T inv = T(1) / T(s);                                                                  \
    return Dual(x.a * inv, x.v * inv);                                                          \
  }                                                                                             \
  friend Dual operator/(const Scalar& s, const Dual& x) {                                       \
    const T inv = T(1) / x.a;                                                                   \
    const T q = T(s) * inv;                                                                     \
    return Dual(q, x.v * T(-q * inv));                                                          \
  }                                                                                             \
  friend bool operator<(const Dual& x, const Scalar& s) { return x.a < s; }                     \
  friend bool operator<(const Scalar& s, const Dual& x) { return s < x.a; }                     \
  friend bool operator<=(const Dual& x, const Scalar& s) { return x.a <= s; }                   \
  friend bool operator<=(const Scalar& s, const Dual& x) { return s <= x.a; }                   \
  friend bool operator>(const Dual& x, const Scalar& s) { return x.a > s; }                     \
  friend bool operator>(const Scalar& s, const Dual& x) { return s > x.a; }                     \
  friend bool operator>=(const Dual& x, const Scalar& s) { return x.a >= s; }                   \
  friend bool operator>=(const Scalar& s, const Dual& x) { return s >= x.a; }                   \
  friend bool operator==(const Dual& x, const Scalar& s) { return x.a == s; }                   \
  friend bool operator!=(const Dual& x, const Scalar& s) { return x.a != s; }
  SALTUS_DUAL_MIXED(double)
  SALTUS_DUAL_MIXED(Lower)
#undef SALTUS_DUAL_MIXED
  Dual& operator+=(const double& s) {
    a += s;
    return *this;
  }
  Dual& operator-=(const double& s) {
    a -= s;
    return *this;
  }
  Dual& operator*=(const double& s) {
    a *= s;
    v *= T(s);
    return *this;
  }
  Dual& operator/=(const double& s) {
    const T inv = T(1) / T(s);
    a *= inv;
    v *= inv;
    return *this;
  }

  // Comparisons: on the value only (a branch does not depend on derivatives).
  friend bool operator<(const Dual& x, const Dual& y) { return x.a < y.a; }
  friend bool operator<=(const Dual& x, const Dual& y) { return x.a <= y.a; }
  friend bool operator>(const Dual& x, const Dual& y) { return x.a > y.a; }
  friend bool operator>=(const Dual& x, const Dual& y) { return x.a >= y.a; }
  friend bool operator==(const Dual& x, const Dual& y) { return x.a == y.a; }
  friend bool operator!=(const Dual& x, const Dual& y) { return x.a != y.a; }

  // ---- elementary functions: f(a + v eps) = f(a) + f'(a) v eps ---------------------------
 private:
  static Dual chain(const Dual& x, const T& f, const T& df) { return Dual(f, x.v * df); }

 public:
  friend Dual sin(const Dual& x) {
    using std::cos;
    using std::sin;
    return chain(x, T(sin(x.a)), T(cos(x.a)));
  }
  friend Dual cos(const Dual& x) {
    using std::cos;
    using std::sin;
    return chain(x, T(cos(x.a)), T(-sin(x.a)));
  }
  friend Dual tan(const Dual& x) {
    using std::tan;
    const T t = tan(x.a);
    return chain(x, t, T(T(1) + t * t));
  }
  friend Dual asin(const Dual& x) {
    using std::asin;
    using std::sqrt;
    return chain(x, T(asin(x.a)), T(T(1) / sqrt(T(1) - x.a * x.a)));
  }
  friend Dual acos(const Dual& x) {
    using std::acos;
    using std::sqrt;
    return chain(x, T(acos(x.a)), T(T(-1) / sqrt(T(1) - x.a * x.a)));
  }
  friend Dual atan(const Dual& x) {
    using std::atan;
    return chain(x, T(atan(x.a)), T(T(1) / (T(1) + x.a * x.a)));
  }
  friend Dual sinh(const Dual& x) {
    using std::cosh;
    using std::sinh;
    return chain(x, T(sinh(x.a)), T(cosh(x.a)));
  }
  friend Dual cosh(const Dual& x) {
    using std::cosh;
    using std::sinh;
    return chain(x, T(cosh(x.a)), T(sinh(x.a)));
  }
  friend Dual tanh(const Dual& x) {
    using std::tanh;
    const T t = tanh(x.a);
    return chain(x, t, T(T(1) - t * t));
  }
  friend Dual exp(const Dual& x) {
    using std::exp;
    const T e = exp(x.a);
    return chain(x, e, e);
  }
  friend Dual log(const Dual& x) {
    using std::log;
    return chain(x, T(log(x.a)), T(T(1) / x.a));
  }
  friend Dual sqrt(const Dual& x) {
    using std::sqrt;
    const T r = sqrt(x.a);
    return chain(x, r, T(T(0.5) / r));
  }
  friend Dual cbrt(const Dual& x) {
    using std::cbrt;
    const T c = cbrt(x.a);
    return chain(x, c, T(T(1) / (T(3) * c * c)));
  }
  /// |x|: the derivative at 0 is taken as 0 (the subgradient that keeps Eigen's pivoting neutral).
  friend Dual abs(const Dual& x) { return x.a < T(0) ? -x : (x.a > T(0) ? x : Dual(x.a)); }
  friend Dual fabs(const Dual& x) { return abs(x); }
  friend Dual atan2(const Dual& y, const Dual& x) {
    using std::atan2;
    const T r2 = x.a * x.a + y.a * y.a;
    return Dual(T(atan2(y.a, x.a)), (y.v * x.a - x.v * y.a) / r2);
  }
  friend Dual atan2(const Dual& y, const double& x) { return atan2(y, Dual(x)); }
  friend Dual atan2(const double& y, const Dual& x) { return atan2(Dual(y), x); }
  friend Dual hypot(const Dual& x, const Dual& y) { return sqrt(x * x + y * y); }
  friend Dual pow(const Dual& x, const double& p) {
    using std::pow;
    return chain(x, T(pow(x.a, T(p))), T(p * pow(x.a, T(p - 1.0))));
  }
  friend Dual pow(const Dual& x, const Dual& p) { return exp(p * log(x)); }
  friend Dual pow(const double& b, const Dual& p) {
    using std::log;
    return exp(p * log(b));
  }
  friend Dual floor(const Dual& x) {
    using std::floor;
    return Dual(T(floor(x.a)));
  }
  friend Dual ceil(const Dual& x) {
    using std::ceil;
    return Dual(T(ceil(x.a)));
  }
  friend Dual fmax(const Dual& x, const Dual& y) { return x < y ? y : x; }
  friend Dual fmin(const Dual& x, const Dual& y) { return y < x ? y : x; }
  friend bool isfinite(const Dual& x) {
    using std::isfinite;
    if (!isfinite(x.a)) return false;
    for (int k = 0; k < N; ++k)
      if (!isfinite(x.v[k])) return false;
    return true;
  }
  friend bool isnan(const Dual& x) {
    using std::isnan;
    if (isnan(x.a)) return true;
    for (int k = 0; k < N; ++k)
      if (isnan(x.v[k])) return true;
    return false;
  }
  friend bool isinf(const Dual& x) {
    using std::isinf;
    return isinf(x.a);
  }
  friend std::ostream& operator<<(std::ostream& os, const Dual& x) {
    os << "[" << x.a << "; " << x.v.transpose() << "]";
    return os;
  }
};

}  // namespace former

namespace Eigen {

template <class T, int N>
struct NumTraits<former::Dual<T, N>> : GenericNumTraits<former::Dual<T, N>> {
  using D = former::Dual<T, N>;
  using Real = D;
  using NonInteger = D;
  using Nested = D;
  using Literal = D;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 1,
    ReadCost = (N + 1) * NumTraits<T>::ReadCost,
    AddCost = (N + 1) * NumTraits<T>::AddCost,
    MulCost = (2 * N + 1) * NumTraits<T>::MulCost
  };
  static inline Real epsilon() { return Real(NumTraits<T>::epsilon()); }
  static inline Real dummy_precision() { return Real(NumTraits<T>::dummy_precision()); }
  static inline Real highest() { return Real(NumTraits<T>::highest()); }
  static inline Real lowest() { return Real(NumTraits<T>::lowest()); }
  static inline Real infinity() { return Real(NumTraits<T>::infinity()); }
  static inline Real quiet_NaN() { return Real(NumTraits<T>::quiet_NaN()); }
  static inline int digits10() { return NumTraits<T>::digits10(); }
  static inline int digits() { return NumTraits<T>::digits(); }
};

// Mixed products Matrix<Dual> * double and double * Matrix<Dual>.
template <class T, int N, typename BinaryOp>
struct ScalarBinaryOpTraits<former::Dual<T, N>, double, BinaryOp> {
  using ReturnType = former::Dual<T, N>;
};
template <class T, int N, typename BinaryOp>
struct ScalarBinaryOpTraits<double, former::Dual<T, N>, BinaryOp> {
  using ReturnType = former::Dual<T, N>;
};

}  // namespace Eigen

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
struct FormerDual {
  using T = former::Dual<double, N>;
  static constexpr const char* name = "former::Dual (baseline)";
  static T seed(double x, int k) { return T(x, k); }
  static double value(const T& t) { return t.a; }
  static double derivative(const T& t, int k) { return t.v[k]; }
};

template <int N>
struct SaltusDual {
  using T = saltus::ad::Dual<double, N>;
  static constexpr const char* name = "saltus::ad::Dual";
  static T seed(double x, int k) { return saltus::ad::seed<N>(x, k); }
  static double value(const T& t) { return t.value(); }
  static double derivative(const T& t, int k) { return t.derivatives()[k]; }
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

/// The scene with its contacts declared frictionless, so that saltus::evaluate_contact computes
/// the normal quantities only (as the baselines here do).
template <class Scene>
struct NormalOnly : Scene {
  NormalOnly() : Scene() {}
  const saltus::ContactSpec& contact(int) const { return spec; }
  saltus::ContactSpec spec{"normal only", saltus::Friction::None, 0.0, 0.0};
};

// ---- the scene functions, called unchanged -----------------------------------------------------

struct HopperGap {
  static constexpr int n = 4, outputs = 1;
  static constexpr const char* name = "hopper_gap";
  static constexpr int contact = 0;
  using SceneType = scenes::Hopper;
  scenes::Hopper scene = scenes::Hopper();
  NormalOnly<scenes::Hopper> normal_only{};
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
  static constexpr int corner = 0, contact = corner;
  using SceneType = scenes::SpatialBox;
  scenes::SpatialBox scene = scenes::SpatialBox();
  NormalOnly<scenes::SpatialBox> normal_only{};
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

struct FormerNested {
  static constexpr const char* name = "former::Dual<Dual<double,nq>,1> (baseline)";
  template <class P>
  static void curvature(const P& p, const Vec<P::n>& q, const Vec<P::n>& v, double* out) {
    constexpr int n = P::n;
    using Inner = former::Dual<double, n>;
    using Outer = former::Dual<Inner, 1>;
    VecT<Outer, n> qs;
    for (int k = 0; k < n; ++k) qs[k] = Outer(Inner(q[k], k), typename Outer::Gradient(Inner(v[k])));
    const Outer g = p.gap(qs);
    out[0] = g.a.a;
    for (int k = 0; k < n; ++k) out[1 + k] = g.a.v[k];
    out[n + 1] = g.v[0].a;
    out[n + 2] = g.v[0].v.dot(v);
  }
};

struct SaltusNested {
  static constexpr const char* name = "saltus::ad::Dual<Dual<double,nq>,1>";
  template <class P>
  static void curvature(const P& p, const Vec<P::n>& q, const Vec<P::n>& v, double* out) {
    constexpr int n = P::n;
    using Inner = saltus::ad::Dual<double, n>;
    using Outer = saltus::ad::Dual<Inner, 1>;
    VecT<Outer, n> qs;
    for (int k = 0; k < n; ++k) qs[k] = Outer(saltus::ad::seed<n>(q[k], k), typename Outer::Gradient(Inner(v[k])));
    const Outer g = p.gap(qs);
    out[0] = g.value().value();
    for (int k = 0; k < n; ++k) out[1 + k] = g.value().derivatives()[k];
    out[n + 1] = g.derivatives()[0].value();
    out[n + 2] = g.derivatives()[0].derivatives().dot(v);
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

// ---- third order: (h, w, zeta, kappa) and their derivatives along (q, v) -------------------------
// out[j * (2n + 1)] is quantity j (h, w_1..w_n, zeta, kappa), out[j * (2n + 1) + 1 + k] its
// derivative along direction k of (q, v).

template <class P>
constexpr int third_order_count = (P::n + 3) * (2 * P::n + 1);

struct FormerThreeLevels {
  static constexpr const char* name = "former::Dual<Dual<Dual<double,2nq>,nq>,1> (baseline)";
  template <class P>
  static void curvature_jacobian(const P& p, const Vec<P::n>& q, const Vec<P::n>& v, double* out) {
    constexpr int n = P::n, m = 2 * P::n;
    using D = former::Dual<double, m>;
    using Inner = former::Dual<D, n>;
    using Outer = former::Dual<Inner, 1>;
    VecT<D, n> qd, vd;
    for (int k = 0; k < n; ++k) {
      qd[k] = D(q[k], k);
      vd[k] = D(v[k], n + k);
    }
    VecT<Outer, n> qs;
    for (int k = 0; k < n; ++k) qs[k] = Outer(Inner(qd[k], k), typename Outer::Gradient(Inner(vd[k])));
    const Outer g = p.gap(qs);
    const D kappa = g.v[0].v.dot(vd);
    std::array<const D*, n + 3> quantities{};
    quantities[0] = &g.a.a;
    for (int k = 0; k < n; ++k) quantities[1 + k] = &g.a.v[k];
    quantities[n + 1] = &g.v[0].a;
    quantities[n + 2] = &kappa;
    for (int j = 0; j < n + 3; ++j) {
      out[j * (m + 1)] = quantities[j]->a;
      for (int k = 0; k < m; ++k) out[j * (m + 1) + 1 + k] = quantities[j]->v[k];
    }
  }
};

/// saltus::evaluate_contact itself (the flow Jacobian's path): three nested levels of saltus::ad::Dual.
struct SaltusThreeLevels {
  static constexpr const char* name = "saltus::ad::Dual<Dual<Dual<double,2nq>,nq>,1>";
  template <class P>
  static void curvature_jacobian(const P& p, const Vec<P::n>& q, const Vec<P::n>& v, double* out) {
    constexpr int n = P::n, m = 2 * P::n;
    using D = saltus::ad::Dual<double, m>;
    VecT<D, n> qd, vd;
    for (int k = 0; k < n; ++k) {
      qd[k] = saltus::ad::seed<m>(q[k], k);
      vd[k] = saltus::ad::seed<m>(v[k], n + k);
    }
    saltus::ContactKinematics<NormalOnly<typename P::SceneType>, D> ck;
    saltus::evaluate_contact(p.normal_only, P::contact, qd, vd, ck);
    std::array<const D*, n + 3> quantities{};
    quantities[0] = &ck.gap;
    for (int k = 0; k < n; ++k) quantities[1 + k] = &ck.wn[k];
    quantities[n + 1] = &ck.zeta_n;
    quantities[n + 2] = &ck.kappa_n;
    for (int j = 0; j < n + 3; ++j) {
      out[j * (m + 1)] = quantities[j]->value();
      for (int k = 0; k < m; ++k) out[j * (m + 1) + 1 + k] = quantities[j]->derivatives()[k];
    }
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
    gradient<FormerDual>(p, s.q[i], ref.data());
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

template <class A, class P>
void check_curvature_jacobian(const P& p) {
  const auto& s = states_for<P>();
  std::array<double, third_order_count<P>> ref{}, got{};
  for (int i = 0; i < kStates; ++i) {
    FormerThreeLevels::curvature_jacobian(p, s.q[i], s.v[i], ref.data());
    A::curvature_jacobian(p, s.q[i], s.v[i], got.data());
    compare(std::string("curvature jacobian ") + P::name + " / " + A::name, i, got.data(), ref.data(),
            third_order_count<P>);
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

template <class A, class P>
void register_curvature_jacobian(const P& p) {
  const std::string name = std::string("curvature_jacobian_") + P::name + "/" + A::name;
  benchmark::RegisterBenchmark(name.c_str(), [p](benchmark::State& state) {
    const auto& s = states_for<P>();
    std::array<double, third_order_count<P>> out{};
    int i = 0;
    for (auto _ : state) {
      A::curvature_jacobian(p, s.q[i], s.v[i], out.data());
      benchmark::DoNotOptimize(out.data());
      benchmark::ClobberMemory();
      i = (i + 1) % kStates;
    }
  });
}

template <class P>
void first_order(const P& p) {
  check_gradient<SaltusDual>(p);
  check_gradient<EigenFixed>(p);
  check_gradient<EigenDynamic>(p);
#ifdef SALTUS_HAVE_CERES_JET
  check_gradient<CeresJet>(p);
#endif
  register_gradient<PlainDouble>(p);
  register_gradient<FormerDual>(p);
  register_gradient<SaltusDual>(p);
  register_gradient<EigenFixed>(p);
  register_gradient<EigenDynamic>(p);
#ifdef SALTUS_HAVE_CERES_JET
  register_gradient<CeresJet>(p);
#endif
}

template <class P, class Scene>
void second_order(const P& p, const Scene& scene, int contact) {
  check_curvature<FormerNested>(p, scene, contact);
  check_curvature<SaltusNested>(p, scene, contact);
  check_curvature<EigenFixedNested>(p, scene, contact);
  check_curvature<EigenDynamicNested>(p, scene, contact);
  register_curvature<FormerNested>(p);
  register_curvature<SaltusNested>(p);
  register_curvature<EigenFixedNested>(p);
  register_curvature<EigenDynamicNested>(p);
}

template <class P>
void third_order(const P& p) {
  check_curvature_jacobian<SaltusThreeLevels>(p);
  register_curvature_jacobian<FormerThreeLevels>(p);
  register_curvature_jacobian<SaltusThreeLevels>(p);
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
  third_order(hopper_gap);
  third_order(box_gap);
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
