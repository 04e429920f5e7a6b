// Forward-mode automatic differentiation for Saltus: Eigen's AutoDiffScalar with a fixed number
// of directions, made to nest to any depth with plain double constants.
//
// Why Eigen's AutoDiffScalar: the project requirement is a well-kept AD library chosen by a
// measurement. bench/ad_choice.cpp (table in bench/README.md) calls the same templated scene
// functions with each candidate: Eigen::AutoDiffScalar<Eigen::Matrix<double, N, 1>> (fixed size)
// was 1.4-1.6x faster than Saltus' former hand-written dual number at one level and 1.1-1.4x at
// two nested levels; the heap-allocating VectorXd form was 4-10x slower; ceres::Jet cannot run
// scene code nested (no double constants below the top level).
//
// Why a thin class and not a bare alias: Saltus nests THREE levels. A contact's curvature
// kappa_n = v^T (d^2 h_n/dq^2) v needs two (kinematics.hpp), and the flow Jacobian differentiates
// that once more along (x, u) (derivatives.hpp):
//     Dual<Dual<Dual<double, nx + nu>, nq>, 1>.
// Eigen's AutoDiffScalar converts a constant only from the next lower level (its `Real`), so at
// the third level a double needs two user-defined conversions, which C++ does not chain:
// `0.5 * x`, `x + 1.0`, `x < 0.0`, `T(0.5)` and even `Matrix<T, 2, 1>::Zero()` (Eigen writes
// `Scalar(0)`) fail to compile (minimal reproduction: tests/test_dual.cpp, file comment).
// Operators alone cannot repair constructors, so Dual<T, N> derives from
// Eigen::AutoDiffScalar<Eigen::Matrix<T, N, 1>> and adds CONSTRUCTORS ONLY: from any lower level
// or arithmetic constant (zero derivatives), and from Eigen's AutoDiffScalar expressions. Every
// arithmetic operator and elementary function is Eigen's own (found by argument-dependent lookup
// through the base class); no derivative rule is written here.
//
// What that leaves to know when writing scene code with T = Dual<...>:
//  - Do not store an AD expression in `auto`: Eigen's operators return expression templates that
//    may refer to temporaries (`auto y = sin(x) + 1.0;` dangles). Write the type: `const T y = ...`.
//  - The elementary functions are Eigen's: abs, abs2, sqrt, exp, log, sin, cos, tan, asin, acos,
//    sinh, cosh, tanh, atan2 (which returns a heap-allocated VectorXd gradient: avoid it on the
//    no-allocation path), min, max, and pow(x, c) at the first level only. Eigen 3.4 has no atan,
//    cbrt, hypot or floor for AutoDiffScalar.
//  - abs'(0) is +1 in Eigen (it was 0 in Saltus' former dual number).
//  - Decompositions (LLT, LU, QR) of nested AD matrices do not compile: Saltus factorises values
//    only (hybrid/contact/linear_solve.hpp).
#pragma once

#include <Eigen/Core>
#include <unsupported/Eigen/AutoDiff>

#include <cmath>
#include <type_traits>

namespace saltus::ad {

template <class T, int N>
class Dual;

/// passive_for_v<S, D>: S is a constant inside D (an arithmetic type or any lower level of D).
template <class S, class D>
struct passive_for : std::false_type {};
template <class S, class T, int N>
struct passive_for<S, Dual<T, N>>
    : std::bool_constant<std::is_arithmetic_v<S> || std::is_same_v<S, T> || passive_for<S, T>::value> {};
template <class S, class D>
inline constexpr bool passive_for_v = passive_for<std::remove_cvref_t<S>, D>::value;

/// Value plus N derivatives: Eigen::AutoDiffScalar<Eigen::Matrix<T, N, 1>> (value(),
/// derivatives()), constructible from constants of any lower level (see the file comment).
template <class T, int N>
class Dual : public Eigen::AutoDiffScalar<Eigen::Matrix<T, N, 1>> {
  using Base = Eigen::AutoDiffScalar<Eigen::Matrix<T, N, 1>>;

 public:
  static_assert(N > 0, "Dual needs at least one direction");
  using value_type = T;
  using Gradient = Eigen::Matrix<T, N, 1>;
  static constexpr int directions = N;

  /// Zero, like the former dual number: `T x{}` and ContactForce<T>{} rely on it. (`= default`
  /// would not do: the base's empty user-provided constructor lets GCC's lifetime dead-store
  /// elimination drop the zero-initialisation of `Dual x{}`.) Each double is written once: at a
  /// nested level, value and derivatives are lower-level Duals this constructor already zeroed.
  Dual() {
    if constexpr (std::is_arithmetic_v<T>) {
      this->value() = T(0);
      this->derivatives().setZero();
    }
  }
  /// A constant: any arithmetic value or lower level, derivatives zero. Implicit on purpose: scene
  /// code mixes double constants in at every level, and Eigen writes Scalar(0), Scalar(1).
  template <class S>
    requires passive_for_v<S, Dual>
  Dual(const S& constant) : Base(T(constant)) {}  // NOLINT(google-explicit-constructor)
  Dual(const T& value, const Gradient& gradient) : Base(value, gradient) {}
  /// The result of Eigen's AD arithmetic (an expression over the same lower level).
  template <class D>
    requires std::is_same_v<typename Eigen::AutoDiffScalar<D>::Scalar, T>
  Dual(const Eigen::AutoDiffScalar<D>& x) : Base(x) {}  // NOLINT(google-explicit-constructor)

  Dual(const Dual&) = default;
  Dual& operator=(const Dual&) = default;
  template <class D>
    requires std::is_same_v<typename Eigen::AutoDiffScalar<D>::Scalar, T>
  Dual& operator=(const Eigen::AutoDiffScalar<D>& x) {
    this->value() = x.value();
    this->derivatives() = x.derivatives();
    return *this;
  }
};

/// The k-th seed: value x, derivative 1 along direction k of N.
template <int N, class T>
Dual<T, N> seed(const T& x, int k) {
  return Dual<T, N>(x, Eigen::Matrix<T, N, 1>::Unit(k));
}

/// Nesting depth: 0 for double, 1 + depth of the inner type for Dual.
template <class T>
struct order : std::integral_constant<int, 0> {};
template <class T, int N>
struct order<Dual<T, N>> : std::integral_constant<int, 1 + order<T>::value> {};
template <class T>
inline constexpr int order_v = order<T>::value;

/// Innermost real value of a possibly nested AD number (or of one of Eigen's AD expressions).
inline double value_of(double x) { return x; }
template <class D>
double value_of(const Eigen::AutoDiffScalar<D>& x) {
  return value_of(x.value());
}

/// Sets the innermost real value, leaving every derivative as it is.
inline void set_value(double& x, double v) { x = v; }
template <class T, int N>
void set_value(Dual<T, N>& x, double v) {
  set_value(x.value(), v);
}

/// True when the value and every derivative, at every level, is finite (bad-input checks).
template <class T, int N>
bool isfinite(const Dual<T, N>& x) {
  using std::isfinite;
  if (!isfinite(x.value())) return false;
  for (int k = 0; k < N; ++k)
    if (!isfinite(x.derivatives()[k])) return false;
  return true;
}
/// True when the value or any derivative, at any level, is NaN.
template <class T, int N>
bool isnan(const Dual<T, N>& x) {
  using std::isnan;
  if (isnan(x.value())) return true;
  for (int k = 0; k < N; ++k)
    if (isnan(x.derivatives()[k])) return true;
  return false;
}

}  // namespace saltus::ad

namespace Eigen {

// Eigen's NumTraits<AutoDiffScalar<...>> does not apply to the derived class. Real = the type
// itself, so norms keep their derivatives. The costs count the N + 1 entries, as Eigen's product
// and unrolling heuristics expect of a scalar this large.
template <class T, int N>
struct NumTraits<saltus::ad::Dual<T, N>> : NumTraits<AutoDiffScalar<Matrix<T, N, 1>>> {
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

// Mixed products with constants (Matrix<Dual> * double, and the lower levels Eigen's own
// operators form internally), as Eigen declares them for AutoDiffScalar.
template <class T, int N, class S, typename BinaryOp>
  requires saltus::ad::passive_for_v<S, saltus::ad::Dual<T, N>>
struct ScalarBinaryOpTraits<saltus::ad::Dual<T, N>, S, BinaryOp> {
  using ReturnType = saltus::ad::Dual<T, N>;
};
template <class T, int N, class S, typename BinaryOp>
  requires saltus::ad::passive_for_v<S, saltus::ad::Dual<T, N>>
struct ScalarBinaryOpTraits<S, saltus::ad::Dual<T, N>, BinaryOp> {
  using ReturnType = saltus::ad::Dual<T, N>;
};

}  // namespace Eigen
