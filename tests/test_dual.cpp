// The AD adapter saltus::ad (hybrid/include/saltus/ad/autodiff.hpp): Eigen's AutoDiffScalar made
// to nest three levels with plain double constants, as the flow Jacobian needs.
//
// Why the adapter exists, as a minimal reproduction: with the bare alias
//     using L3 = AutoDiffScalar<Matrix<AutoDiffScalar<Matrix<AutoDiffScalar<Matrix<double, 10, 1>>, 4, 1>>, 1, 1>>;
// Eigen 3.4 rejects `0.5 * x`, `x + 1.0`, `x < 0.0` and `L3(0.5)` ("no match for operator*",
// "no matching function for call to AutoDiffScalar(double)"), and `Matrix<L3, 2, 1>::Zero()`
// fails inside CwiseNullaryOp.h (Eigen writes Scalar(0)): a double reaches the third level only
// through two user-defined conversions. PlainAutoDiffScalarDoesNotNestConstants checks the part
// of this that is detectable at compile time, so that a future Eigen which fixes it is noticed.
#include <saltus/ad/autodiff.hpp>
#include <saltus/ad/compose.hpp>
#include <saltus/hybrid/contact/linear_solve.hpp>
#include <saltus/hybrid/dynamics/kinematics.hxx>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

namespace {

using saltus::ad::Dual;
using saltus::ad::seed;
using saltus::ad::value_of;
using D1 = Dual<double, 1>;
using D2 = Dual<D1, 1>;
using D3 = Dual<D2, 1>;

template <class T, int N>
using Plain = Eigen::AutoDiffScalar<Eigen::Matrix<T, N, 1>>;
using Plain3 = Plain<Plain<Plain<double, 10>, 4>, 1>;
using Plain2 = Plain<Plain<double, 10>, 4>;

template <class X>
constexpr bool multiplies_by_double = requires(const X& x) { 0.5 * x; };
template <class X>
constexpr bool adds_double = requires(const X& x) { x + 1.0; };
template <class X>
constexpr bool compares_with_double = requires(const X& x) { x < 0.0; };

TEST(AutoDiff, PlainAutoDiffScalarDoesNotNestConstants) {
  // Two levels mix with doubles; three do not (the reason for saltus::ad::Dual's constructors).
  EXPECT_TRUE((std::is_constructible_v<Plain2, double>));
  EXPECT_TRUE(multiplies_by_double<Plain2>);
  EXPECT_FALSE((std::is_constructible_v<Plain3, double>))
      << "Eigen now lifts a double through three levels: saltus::ad::Dual could become an alias";
  EXPECT_FALSE(multiplies_by_double<Plain3>);
  EXPECT_FALSE(adds_double<Plain3>);
  EXPECT_FALSE(compares_with_double<Plain3>);
  // The adapter at the same depth (the flow Jacobian's scalar of a hopper contact).
  using A3 = Dual<Dual<Dual<double, 10>, 4>, 1>;
  EXPECT_TRUE((std::is_constructible_v<A3, double>));
  EXPECT_TRUE((std::is_convertible_v<double, A3>));
  EXPECT_TRUE((std::is_convertible_v<int, A3>));
  EXPECT_TRUE((std::is_convertible_v<Dual<double, 10>, A3>));
  EXPECT_FALSE((std::is_convertible_v<A3, Dual<double, 10>>));
  EXPECT_TRUE(multiplies_by_double<A3>);
  EXPECT_TRUE(adds_double<A3>);
  EXPECT_TRUE(compares_with_double<A3>);
}

TEST(AutoDiff, OrderAndSeeds) {
  static_assert(saltus::ad::order_v<double> == 0);
  static_assert(saltus::ad::order_v<D1> == 1);
  static_assert(saltus::ad::order_v<Dual<Dual<Dual<double, 10>, 4>, 1>> == 3);
  const Dual<double, 3> x = seed<3>(0.25, 1);
  EXPECT_EQ(x.value(), 0.25);
  EXPECT_EQ(x.derivatives(), Eigen::Vector3d(0, 1, 0));
  // A seed one level up: the value is itself a seeded level.
  const Dual<Dual<double, 3>, 2> y = seed<2>(x, 0);
  EXPECT_EQ(y.value().value(), 0.25);
  EXPECT_EQ(y.value().derivatives(), Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(y.derivatives()[0].value(), 1.0);
  EXPECT_EQ(y.derivatives()[0].derivatives(), Eigen::Vector3d::Zero());
  EXPECT_EQ(y.derivatives()[1].value(), 0.0);
}

/// Largest |entry| over the value and every derivative at every level; and over the
/// derivatives only.
double largest(double x) { return std::abs(x); }
template <class T, int N>
double largest(const Dual<T, N>& x) {
  double m = largest(x.value());
  for (int k = 0; k < N; ++k) m = std::max(m, largest(x.derivatives()[k]));
  return m;
}
template <class T, int N>
double largest_derivative(const Dual<T, N>& x) {
  double m = 0.0;
  if constexpr (saltus::ad::order_v<T> > 0) m = largest_derivative(x.value());
  for (int k = 0; k < N; ++k) m = std::max(m, largest(x.derivatives()[k]));
  return m;
}

TEST(AutoDiff, ConstantsAndValueInitialisationAreZeroAtEveryLevel) {
  using A3 = Dual<Dual<Dual<double, 5>, 3>, 2>;
  const A3 z{};
  EXPECT_EQ(largest(z), 0.0);
  const A3 c = 2.5;
  EXPECT_EQ(value_of(c), 2.5);
  EXPECT_EQ(largest_derivative(c), 0.0);
  const A3 i = 3;
  EXPECT_EQ(value_of(i), 3.0);
  EXPECT_EQ(largest_derivative(i), 0.0);
  // A lower level as a constant keeps its own derivatives and gets zero ones above.
  const A3 m = seed<5>(1.0, 2);
  EXPECT_EQ(m.value().value().derivatives()[2], 1.0);
  EXPECT_EQ(largest_derivative(m.value()), 1.0);
  EXPECT_EQ(largest(m.derivatives()[0]), 0.0);
  EXPECT_EQ(largest(m.derivatives()[1]), 0.0);
  struct Force {
    A3 normal{};
  };
  const Force f{};
  EXPECT_EQ(largest(f.normal), 0.0);
  const Eigen::Matrix<A3, 2, 2> I = Eigen::Matrix<A3, 2, 2>::Identity();
  EXPECT_EQ(value_of(I(0, 0)), 1.0);
  EXPECT_EQ(largest(I(1, 0)), 0.0);
  EXPECT_EQ(largest_derivative(I(1, 1)), 0.0);
}

/// f(x) with a generic body: the explicit return type evaluates Eigen's expression before the
/// argument goes out of scope (returning `auto` here would dangle: see autodiff.hpp).
template <class F>
void expect_derivative(const char* name, F f, double x) {
  const D1 r = f(seed<1>(x, 0));
  const double h = 1e-6;
  const double fd = (f(x + h) - f(x - h)) / (2 * h);
  EXPECT_NEAR(r.value(), f(x), 1e-15 * (1 + std::abs(f(x)))) << name;
  EXPECT_NEAR(r.derivatives()[0], fd, 1e-7 * (1 + std::abs(fd))) << name << " at x = " << x;
}

#define SALTUS_AD_CASE(name, body) expect_derivative(name, [](auto s) -> decltype(s) { return body; }, x)

TEST(AutoDiff, EigensElementaryFunctionsMatchCentralDifferences) {
  using std::abs, std::acos, std::asin, std::atan2, std::cos, std::cosh, std::exp, std::log, std::pow,
      std::sin, std::sinh, std::sqrt, std::tan, std::tanh;
  for (double x : {-0.7, 0.3, 0.61}) {
    SALTUS_AD_CASE("sin", sin(s));
    SALTUS_AD_CASE("cos", cos(s));
    SALTUS_AD_CASE("tan", tan(s));
    SALTUS_AD_CASE("asin", asin(s));
    SALTUS_AD_CASE("acos", acos(s));
    SALTUS_AD_CASE("sinh", sinh(s));
    SALTUS_AD_CASE("cosh", cosh(s));
    SALTUS_AD_CASE("tanh", tanh(s));
    SALTUS_AD_CASE("exp", exp(s));
    SALTUS_AD_CASE("abs", abs(s));
    SALTUS_AD_CASE("atan2(y, c)", atan2(s, 0.4 + 0 * s));
    SALTUS_AD_CASE("atan2(c, x)", atan2(0.4 + 0 * s, s));
    SALTUS_AD_CASE("rational", (1.0 + s * s) / (2.0 - s) - 3.0 / (s + 4.0) + 2 * s - s / 5.0);
  }
  for (double x : {0.3, 1.7}) {
    SALTUS_AD_CASE("log", log(s));
    SALTUS_AD_CASE("sqrt", sqrt(s));
    SALTUS_AD_CASE("pow(x, 2.5)", pow(s, 2.5));
  }
}
#undef SALTUS_AD_CASE

// The scalar type the flow Jacobian runs scene code with, in miniature: three levels, each seeded
// along x, double constants and comparisons at every level, T(c) and Zero() inside.
template <class T>
T scene_like(const T& x) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  Eigen::Matrix<T, 2, 1> p = Eigen::Matrix<T, 2, 1>::Zero();
  p[0] = 0.5 * x * sin(x) + 1.0;
  p[1] = T(0.25) - cos(x) / 2.0 + 3 * x;
  T y = p[0] * p[1] - 1.0 / (x + 4.0);
  if (x < 0.0 || 0.0 > x) y = -y;
  y += 0.5;
  y *= 2.0;
  y -= 1.0;
  y /= 4.0;
  return y + sqrt(p.squaredNorm() + 1.0) + Eigen::Matrix<T, 2, 2>::Identity().trace();
}

double scene_like_d(double x, int order) {
  // Central differences of central differences: order 0..3.
  if (order == 0) return scene_like(x);
  const double h = 1e-3;
  return (scene_like_d(x + h, order - 1) - scene_like_d(x - h, order - 1)) / (2 * h);
}

TEST(AutoDiff, ThreeNestedLevelsWithDoubleConstantsGiveThreeDerivatives) {
  for (double x : {-0.6, 0.35, 1.1}) {
    const D1 s1 = seed<1>(x, 0);
    const D2 s2(s1, D2::Gradient::Constant(D1(1.0)));
    const D3 s3(s2, D3::Gradient::Constant(D2(D1(1.0))));
    const D3 f = scene_like(s3);
    EXPECT_NEAR(value_of(f), scene_like(x), 1e-14 * (1 + std::abs(scene_like(x))));
    // The same derivative sits on every path through the levels (symmetry of mixed partials).
    const double d1 = f.derivatives()[0].value().value();
    EXPECT_EQ(d1, f.value().derivatives()[0].value());
    EXPECT_EQ(d1, f.value().value().derivatives()[0]);
    const double d2 = f.derivatives()[0].derivatives()[0].value();
    EXPECT_NEAR(d2, f.derivatives()[0].value().derivatives()[0], 1e-13 * (1 + std::abs(d2)));
    const double d3 = f.derivatives()[0].derivatives()[0].derivatives()[0];
    EXPECT_NEAR(d1, scene_like_d(x, 1), 1e-5 * (1 + std::abs(d1)));
    EXPECT_NEAR(d2, scene_like_d(x, 2), 1e-4 * (1 + std::abs(d2)));
    EXPECT_NEAR(d3, scene_like_d(x, 3), 1e-3 * (1 + std::abs(d3)));
    // The value path of the double function, bit for bit (the same operations on the values).
    EXPECT_EQ(value_of(scene_like(s1)), value_of(f));
  }
}

TEST(AutoDiff, ExactThirdDerivativeOfAPolynomialTimesSine) {
  // f(x) = 0.5 sin(x) x^2: f' = 0.5 (cos x x^2 + 2x sin x), f'' = 0.5 (-sin x x^2 + 4x cos x + 2 sin x),
  // f''' = 0.5 (-cos x x^2 - 6x sin x + 6 cos x).
  using std::sin;
  const double x = 0.8;
  const D3 s(D2(seed<1>(x, 0), D2::Gradient::Constant(D1(1.0))), D3::Gradient::Constant(D2(D1(1.0))));
  const D3 f = 0.5 * sin(s) * s * s;
  EXPECT_NEAR(f.value().value().value(), 0.5 * std::sin(x) * x * x, 1e-15);
  EXPECT_NEAR(f.derivatives()[0].value().value(), 0.5 * (std::cos(x) * x * x + 2 * x * std::sin(x)), 1e-14);
  EXPECT_NEAR(f.derivatives()[0].derivatives()[0].value(),
              0.5 * (-std::sin(x) * x * x + 4 * x * std::cos(x) + 2 * std::sin(x)), 1e-14);
  EXPECT_NEAR(f.derivatives()[0].derivatives()[0].derivatives()[0],
              0.5 * (-std::cos(x) * x * x - 6 * x * std::sin(x) + 6 * std::cos(x)), 1e-14);
}

TEST(AutoDiff, ValueOfReachesTheInnermostDouble) {
  EXPECT_EQ(value_of(1.5), 1.5);
  const Dual<Dual<Dual<double, 4>, 3>, 2> x = 0.75;
  EXPECT_EQ(value_of(x), 0.75);
  const Dual<double, 4> y = seed<4>(2.0, 3);
  EXPECT_EQ(value_of(y * y + 1.0), 5.0);  // of an Eigen expression as well
  Dual<Dual<double, 4>, 3> z = seed<3>(y, 1);
  saltus::ad::set_value(z, -1.0);
  EXPECT_EQ(value_of(z), -1.0);
  EXPECT_EQ(z.value().derivatives()[3], 1.0);  // derivatives untouched
  EXPECT_EQ(z.derivatives()[1].value(), 1.0);
}

TEST(AutoDiff, IsFiniteLooksAtEveryDerivativeOfEveryLevel) {
  using A3 = Dual<Dual<Dual<double, 3>, 2>, 1>;
  A3 x = 1.0;
  EXPECT_TRUE(isfinite(x));
  EXPECT_FALSE(isnan(x));
  x.derivatives()[0].derivatives()[1].derivatives()[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(isfinite(x));
  EXPECT_TRUE(isnan(x));
  EXPECT_EQ(value_of(x), 1.0);
  A3 y = 1.0;
  y.value().value().derivatives()[0] = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(isfinite(y));
  EXPECT_FALSE(isnan(y));
  using std::sqrt;
  const A3 r = sqrt(A3(0.0) + A3(seed<2>(Dual<double, 3>(0.0), 0)));  // sqrt'(0) = inf
  EXPECT_TRUE(std::isfinite(value_of(r)));
  EXPECT_FALSE(isfinite(r));
  // Eigen's allFinite() on AD matrices looks at values only (flow.hpp's check is on values).
  Eigen::Matrix<A3, 2, 1> v(A3(1.0), x);
  EXPECT_TRUE(v.allFinite());
  v[1] = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(v.allFinite());
}

TEST(AutoDiff, ValueFactorisationSolveGivesSecondDerivatives) {
  // x(p) = A(p)^{-1} b(p) by saltus::solve_with_value_factorization (factorises value(A) only):
  // first and second derivatives against central differences of the double solve.
  auto build = [](auto p, Eigen::Matrix<decltype(p), 3, 3>& A, Eigen::Matrix<decltype(p), 3, 1>& b) {
    using std::cos;
    using std::sin;
    using T = decltype(p);
    A << 4.0 + p, sin(p), T(0.5), sin(p), T(3.0), p * p, T(0.5), p * p, 2.0 + cos(p);
    b << T(1.0), p, T(2.0);
  };
  auto solve = [&](auto p) {
    using T = decltype(p);
    Eigen::Matrix<T, 3, 3> A;
    Eigen::Matrix<T, 3, 1> b, x, work;
    build(p, A, b);
    Eigen::Matrix3d A0;
    saltus::ad::value_into(A, A0);
    const Eigen::PartialPivLU<Eigen::Matrix3d> lu(A0);
    saltus::solve_with_value_factorization(A, b, [&](auto& v) { v = lu.solve(v).eval(); }, x, work);
    return x;
  };
  const double p0 = 0.37, h = 1e-4;
  const auto x2 = solve(D2(seed<1>(p0, 0), D2::Gradient::Constant(D1(1.0))));
  for (int i = 0; i < 3; ++i) {
    const double x0 = solve(p0)[i], xp = solve(p0 + h)[i], xm = solve(p0 - h)[i];
    EXPECT_NEAR(value_of(x2[i]), x0, 1e-15);
    EXPECT_NEAR(x2[i].value().derivatives()[0], (xp - xm) / (2 * h), 1e-7) << "first derivative, entry " << i;
    EXPECT_NEAR(x2[i].derivatives()[0].derivatives()[0], (xp - 2 * x0 + xm) / (h * h), 1e-5)
        << "second derivative, entry " << i;
  }
}

}  // namespace

// GCC 12.2 -O3 wrong code in the nested-dual contact kinematics (the reason Release was -O2).
// The reduced reproducer: a box corner over a tilting plank (the plank-box's contact C_L, down to
// what the miscompilation needs), planar friction, evaluate_contact instantiated in this
// translation unit for a scene of its own (with external linkage: in the anonymous namespace
// GCC's inlining differs and the loop below compiled correctly), called directly and its results
// read back. evaluate_contact had:
//
//   const int nt = scene.contact(i).tangents();            // 1 here, unknown to the compiler
//   const VecT<Outer, 2> tp = scene.tangent_position<Outer>(i, qs);
//   for (int k = 0; k < nt; ++k) {
//     out.Wt.col(k) = tp[k].value().derivatives();          // stride 4 doubles
//     out.zeta_t[k] = tp[k].derivatives()[0].value();       // stride 1 double
//     out.kappa_t[k] = tp[k].derivatives()[0].derivatives().dot(v);
//   }
//
// IVOPTs gives the three stores one induction variable iv = &out + 8 k and writes the W_t store
// as MEM[(__m128d *)0B + 64 + (-3 &out) + 4 iv] (a TARGET_MEM_REF whose base is the constant 0).
// The late modref pass (-fdump-tree-modref2) takes that for a null dereference ("NULL memory
// access; terminating BB"), stops analysing the loop body there, and records a summary in which
// evaluate_contact stores none of W_t, zeta_t, kappa_t. The caller's value numbering trusts the
// summary and reads back the zeros ContactKinematics' constructor wrote: W_t = 0, zeta_t = 0,
// kappa_t = 0 (at run time the stores did happen). Here W_t(q +- h v) was read back as 0, so the
// central difference of W_t^T v came out exactly 0, as in the scene battery. No undefined
// behaviour is involved: UBSan and ASan builds are correct, -fno-strict-aliasing does not cure it;
// -fno-ipa-modref, -fno-tree-fre or -fno-tree-pre do, and GCC 12.2 -O2 and clang 14 -O3 are
// correct. Without the gap evaluation before the loop, or with the loop unrolled by hand, the
// null-based reference is not formed. evaluate_contact (kinematics.hxx) now stores the two
// tangents without a loop; with the loop put back this test fails at -O3 (GCC 12.2) unless
// -fno-ipa-modref is given, which saltus::hybrid now passes on (hybrid/CMakeLists.txt).
namespace gcc_modref_repro {

struct TiltedCorner {
  static constexpr int nq = 4, nu = 0, nc = 1;  // box x, y, angle; plank angle
  saltus::ContactSpec spec{"corner", saltus::Friction::Planar, 0.4, 0.0};
  const saltus::ContactSpec& contact(int) const { return spec; }
  template <class T>
  saltus::MatT<T, nq, nq> mass_matrix(const saltus::VecT<T, nq>&) const {
    return saltus::MatT<T, nq, nq>::Identity();
  }
  template <class T>
  saltus::VecT<T, nq> bias(const saltus::VecT<T, nq>&, const saltus::VecT<T, nq>&) const {
    return saltus::VecT<T, nq>::Zero();
  }
  template <class T>
  saltus::MatT<T, nq, nu> input_matrix(const saltus::VecT<T, nq>&) const {
    return {};
  }
  double length = 0.3, height = 0.1, thickness = 0.02;
  /// The box's bottom-left corner in world coordinates.
  template <class T>
  saltus::VecT<T, 2> corner(int i, const saltus::VecT<T, nq>& q) const {
    using std::cos;
    using std::sin;
    const double rx = (i == 0 ? -0.5 : 0.5) * length, ry = -0.5 * height;
    const T c = cos(q[2]), s = sin(q[2]);
    return saltus::VecT<T, 2>(q[0] + c * rx - s * ry, q[1] + s * rx + c * ry);
  }
  /// The corner in the frame of the plank tilted by q[3].
  template <class T>
  saltus::VecT<T, 2> in_plank(int i, const saltus::VecT<T, nq>& q) const {
    using std::cos;
    using std::sin;
    const saltus::VecT<T, 2> p = corner(i, q);
    const T c = cos(q[3]), s = sin(q[3]);
    return saltus::VecT<T, 2>(c * p[0] + s * p[1], -s * p[0] + c * p[1]);
  }
  template <class T>
  T gap(int i, const saltus::VecT<T, nq>& q) const {
    return in_plank(i, q)[1] - 0.5 * thickness;
  }
  template <class T>
  saltus::VecT<T, 2> tangent_position(int i, const saltus::VecT<T, nq>& q) const {
    return saltus::VecT<T, 2>(in_plank(i, q)[0], T(0));
  }
};

}  // namespace gcc_modref_repro

namespace {

using gcc_modref_repro::TiltedCorner;

TEST(GccModrefNullBaseLoop, ContactTangentTermsSurviveO3) {
  const TiltedCorner scene;
  const Eigen::Vector4d q(0.1, 0.2, 0.3, 0.4), v(0.5, -0.7, 1.1, 0.9);
  saltus::ContactKinematics<TiltedCorner> c;
  saltus::evaluate_contact(scene, 0, q, v, c);
  ASSERT_EQ(c.tangents, 1);
  const double h = 1e-6;
  auto tangent = [&](const Eigen::Vector4d& p) { return scene.tangent_position<double>(0, p)[0]; };
  Eigen::Vector4d wt_fd;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector4d e = h * Eigen::Vector4d::Unit(k);
    wt_fd[k] = (tangent(q + e) - tangent(q - e)) / (2 * h);
  }
  EXPECT_TRUE(c.Wt.col(0).isApprox(wt_fd, 1e-8)) << "W_t = " << c.Wt.col(0).transpose() << ", expected "
                                                  << wt_fd.transpose();
  EXPECT_NEAR(c.zeta_t[0], wt_fd.dot(v), 1e-8);
  // kappa_t = d/ds (W_t(q + s v) . v) at s = 0, against a central difference of AD Jacobians.
  saltus::ContactKinematics<TiltedCorner> cp, cm;
  saltus::evaluate_contact(scene, 0, Eigen::Vector4d(q + h * v), v, cp);
  saltus::evaluate_contact(scene, 0, Eigen::Vector4d(q - h * v), v, cm);
  const double kappa_fd = (cp.Wt.col(0).dot(v) - cm.Wt.col(0).dot(v)) / (2 * h);
  EXPECT_NE(kappa_fd, 0.0);
  EXPECT_NEAR(c.kappa_t[0], kappa_fd, 1e-7 * (1 + std::abs(kappa_fd)));
  EXPECT_EQ(c.Wt.col(1), Eigen::Vector4d::Zero());
}

}  // namespace

// ad::compose: a function of n variables inside a computation along N > n directions, by the chain
// rule (the FESD callbacks' contact kinematics). It must give the derivatives of the direct
// evaluation at every order, for inputs whose own derivatives are not seeds (curved x(z)), and
// through an AD level inside f (as the kinematics' Jacobians are).
namespace {

template <class T>
Eigen::Matrix<T, 6, 1> seeds_of(const Eigen::Matrix<double, 6, 1>& z);
template <>
Eigen::Matrix<Dual<double, 6>, 6, 1> seeds_of(const Eigen::Matrix<double, 6, 1>& z) {
  Eigen::Matrix<Dual<double, 6>, 6, 1> out;
  for (int k = 0; k < 6; ++k) out[k] = seed<6>(z[k], k);
  return out;
}
template <>
Eigen::Matrix<Dual<Dual<double, 6>, 6>, 6, 1> seeds_of(const Eigen::Matrix<double, 6, 1>& z) {
  Eigen::Matrix<Dual<Dual<double, 6>, 6>, 6, 1> out;
  for (int k = 0; k < 6; ++k) {
    Eigen::Matrix<Dual<double, 6>, 6, 1> outer;
    for (int j = 0; j < 6; ++j) outer[j] = Dual<double, 6>(j == k ? 1.0 : 0.0);
    out[k] = Dual<Dual<double, 6>, 6>(seed<6>(z[k], k), outer);
  }
  return out;
}

// x(z): curved, so x's second derivatives are not zero (compose's sum_a g_a E_a term).
template <class T>
Eigen::Matrix<T, 3, 1> curved_inputs(const Eigen::Matrix<T, 6, 1>& z) {
  using std::sin;
  return Eigen::Matrix<T, 3, 1>(T(z[0] * z[1]), T(sin(z[2]) + z[3]), T(z[4] * z[4] * z[5]));
}

// f: R^3 -> R^3, one output a derivative taken by AD inside f.
struct WithInnerDerivative {
  template <class S>
  Eigen::Matrix<S, 3, 1> operator()(const Eigen::Matrix<S, 3, 1>& x) const {
    using std::exp;
    using std::sin;
    Eigen::Matrix<Dual<S, 3>, 3, 1> xd;
    for (int a = 0; a < 3; ++a) xd[a] = seed<3>(x[a], a);
    const Dual<S, 3> inner = exp(xd[0] * xd[2]) + xd[1] * xd[1] * xd[2];
    return Eigen::Matrix<S, 3, 1>(S(sin(x[0]) * x[1] + x[2] * x[2]), inner.derivatives()[0], inner.derivatives()[2]);
  }
};

template <class T>
void expect_same_derivatives(const T& a, const T& b) {
  if constexpr (std::is_same_v<T, double>) {
    EXPECT_NEAR(a, b, 1e-13 * (1.0 + std::abs(b)));
  } else {
    expect_same_derivatives(a.value(), b.value());
    for (int k = 0; k < a.derivatives().size(); ++k) expect_same_derivatives(a.derivatives()[k], b.derivatives()[k]);
  }
}

template <class T>
void expect_compose_matches_direct() {
  const Eigen::Matrix<double, 6, 1> z(0.3, -0.8, 0.5, 1.2, -0.4, 0.9);
  const Eigen::Matrix<T, 3, 1> x = curved_inputs<T>(seeds_of<T>(z));
  const Eigen::Matrix<T, 3, 1> direct = WithInnerDerivative{}(x);
  const Eigen::Matrix<T, 3, 1> composed = saltus::ad::compose(x, WithInnerDerivative{});
  for (int i = 0; i < 3; ++i) expect_same_derivatives(composed[i], direct[i]);
}

TEST(AdCompose, FirstOrderMatchesTheDirectEvaluation) { expect_compose_matches_direct<Dual<double, 6>>(); }

TEST(AdCompose, SecondOrderMatchesTheDirectEvaluationForCurvedInputs) {
  expect_compose_matches_direct<Dual<Dual<double, 6>, 6>>();
}

TEST(AdCompose, SecondOrderMatchesForSeededInputs) {
  // x = (z_0, z_1, z_2) themselves: the FESD Hessian's case (seeds, no curvature).
  using T = Dual<Dual<double, 6>, 6>;
  const Eigen::Matrix<T, 6, 1> z = seeds_of<T>(Eigen::Matrix<double, 6, 1>(0.3, -0.8, 0.5, 1.2, -0.4, 0.9));
  const Eigen::Matrix<T, 3, 1> x = z.head<3>();
  const Eigen::Matrix<T, 3, 1> direct = WithInnerDerivative{}(x);
  const Eigen::Matrix<T, 3, 1> composed = saltus::ad::compose(x, WithInnerDerivative{});
  for (int i = 0; i < 3; ++i) expect_same_derivatives(composed[i], direct[i]);
}

TEST(AdCompose, FewerDirectionsThanInputsAndDoublesEvaluateDirectly) {
  const Eigen::Vector3d x0(0.3, -0.8, 0.5);
  const Eigen::Vector3d direct = WithInnerDerivative{}(x0);
  EXPECT_EQ(saltus::ad::compose(x0, WithInnerDerivative{}), direct);
  // N = 2 < n = 3: nothing to save, f runs at x's own type (the fall-back overload).
  Eigen::Matrix<Dual<double, 2>, 3, 1> x;
  for (int a = 0; a < 3; ++a) x[a] = Dual<double, 2>(x0[a], Eigen::Vector2d(a + 1.0, 0.5 * a));
  const Eigen::Matrix<Dual<double, 2>, 3, 1> composed = saltus::ad::compose(x, WithInnerDerivative{});
  const Eigen::Matrix<Dual<double, 2>, 3, 1> expected = WithInnerDerivative{}(x);
  for (int i = 0; i < 3; ++i) expect_same_derivatives(composed[i], expected[i]);
}

}  // namespace
