// Forward-mode automatic differentiation with a fixed number of directions.
//
// Why Saltus has its own dual number, and what the measurement says (bench/ad_choice.cpp, table
// in bench/README.md): the scene functions are differentiated to second order (the curvature
// term v^T (d^2 h_n/dq^2) v of a contact) and, for jump gains, to third order (the flow Jacobian
// differentiates the curvature once more). That needs a scalar type that nests
// (Dual<Dual<double, n>, 1>) and accepts plain double constants at every nesting level (scene
// code writes `0.5 * l * cos(phi)`). ceres::Jet does not accept such constants when nested;
// Sacado needs Kokkos and Trilinos. Eigen's fixed-size AutoDiffScalar does nest with constants at
// two levels and is measured 1.1-1.6x FASTER than this Dual per call; this type is kept for now
// because the value-factorisation solves (linear_solve.hpp) and every kernel use its plain layout
// (value `a`, gradient `v`) and three-level nesting; porting to AutoDiffScalar is an open,
// measured follow-up. Dual<T, N> is a value plus a fixed-size Eigen gradient (no heap, no
// expression templates, so `auto` in scene code is safe) with the nesting rules added.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <limits>
#include <ostream>
#include <type_traits>

namespace saltus::ad {

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

template <class T>
struct is_dual : std::false_type {};
template <class T, int N>
struct is_dual<Dual<T, N>> : std::true_type {};
template <class T>
inline constexpr bool is_dual_v = is_dual<std::remove_cvref_t<T>>::value;

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

}  // namespace saltus::ad

namespace Eigen {

template <class T, int N>
struct NumTraits<saltus::ad::Dual<T, N>> : GenericNumTraits<saltus::ad::Dual<T, N>> {
  using D = saltus::ad::Dual<T, N>;
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
struct ScalarBinaryOpTraits<saltus::ad::Dual<T, N>, double, BinaryOp> {
  using ReturnType = saltus::ad::Dual<T, N>;
};
template <class T, int N, typename BinaryOp>
struct ScalarBinaryOpTraits<double, saltus::ad::Dual<T, N>, BinaryOp> {
  using ReturnType = saltus::ad::Dual<T, N>;
};

}  // namespace Eigen
