// The dual number against central finite differences: every elementary function, nesting to
// second and third order, and derivatives through Eigen's decompositions.
#include <saltus/ad/dual.hpp>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

namespace {

using saltus::ad::Dual;
using D1 = Dual<double, 1>;

double central_difference(const std::function<double(double)>& f, double x, double h = 1e-6) {
  return (f(x + h) - f(x - h)) / (2 * h);
}

template <class F>
void expect_derivative(const char* name, F f, double x) {
  const D1 r = f(D1(x, 0));
  const double fd = central_difference([&](double s) { return f(s); }, x);
  EXPECT_NEAR(r.a, f(x), 1e-15 * (1 + std::abs(r.a))) << name;
  EXPECT_NEAR(r.v[0], fd, 1e-7 * (1 + std::abs(fd))) << name << " at x = " << x;
}

TEST(Dual, ElementaryFunctionsMatchCentralDifferences) {
  using std::abs, std::acos, std::asin, std::atan, std::atan2, std::cbrt, std::cos, std::cosh,
      std::exp, std::hypot, std::log, std::pow, std::sin, std::sinh, std::sqrt, std::tan, std::tanh;
  for (double x : {-0.7, 0.3, 0.61}) {
    expect_derivative("sin", [](auto s) { return sin(s); }, x);
    expect_derivative("cos", [](auto s) { return cos(s); }, x);
    expect_derivative("tan", [](auto s) { return tan(s); }, x);
    expect_derivative("asin", [](auto s) { return asin(s); }, x);
    expect_derivative("acos", [](auto s) { return acos(s); }, x);
    expect_derivative("atan", [](auto s) { return atan(s); }, x);
    expect_derivative("sinh", [](auto s) { return sinh(s); }, x);
    expect_derivative("cosh", [](auto s) { return cosh(s); }, x);
    expect_derivative("tanh", [](auto s) { return tanh(s); }, x);
    expect_derivative("exp", [](auto s) { return exp(s); }, x);
    expect_derivative("abs", [](auto s) { return abs(s); }, x);
    expect_derivative("cbrt", [](auto s) { return cbrt(s); }, x);
    expect_derivative("atan2(y,c)", [](auto s) { return atan2(s, 0.4 + 0 * s); }, x);
    expect_derivative("atan2(c,x)", [](auto s) { return atan2(0.4 + 0 * s, s); }, x);
    expect_derivative("hypot", [](auto s) { return hypot(s, 2.0 * s + 1.0); }, x);
    expect_derivative("rational", [](auto s) { return (1.0 + s * s) / (2.0 - s) - 3.0 / (s + 4.0); }, x);
  }
  for (double x : {0.3, 1.7}) {
    expect_derivative("log", [](auto s) { return log(s); }, x);
    expect_derivative("sqrt", [](auto s) { return sqrt(s); }, x);
    expect_derivative("pow(x,2.5)", [](auto s) { return pow(s, 2.5); }, x);
    expect_derivative("pow(x,x)", [](auto s) { return pow(s, s); }, x);
    expect_derivative("pow(2,x)", [](auto s) { return pow(2.0, s) + 0.0 * s; }, x);
  }
}

TEST(Dual, NestedGivesSecondAndThirdDerivatives) {
  // f(x) = sin(x) x^2: f' = cos x x^2 + 2x sin x, f'' = -sin x x^2 + 4x cos x + 2 sin x,
  // f''' = -cos x x^2 - 6x sin x + 6 cos x.
  using D2 = Dual<D1, 1>;
  using D3 = Dual<D2, 1>;
  const double x = 0.8;
  const D3 s(D2(D1(x, 0), D2::Gradient::Constant(D1(1.0))), D3::Gradient::Constant(D2(D1(1.0))));
  using std::sin;
  const D3 f = sin(s) * s * s * 1.0;
  const double f1 = std::cos(x) * x * x + 2 * x * std::sin(x);
  const double f2 = -std::sin(x) * x * x + 4 * x * std::cos(x) + 2 * std::sin(x);
  const double f3 = -std::cos(x) * x * x - 6 * x * std::sin(x) + 6 * std::cos(x);
  EXPECT_NEAR(f.a.a.a, std::sin(x) * x * x, 1e-15);
  EXPECT_NEAR(f.v[0].a.a, f1, 1e-14);
  EXPECT_NEAR(f.v[0].v[0].a, f2, 1e-14);
  EXPECT_NEAR(f.v[0].v[0].v[0], f3, 1e-13);
}

TEST(Dual, DerivativeThroughDecompositionsMatchesFiniteDifferences) {
  // x(p) = A(p)^{-1} b(p) solved by LLT, LU and complete orthogonal decomposition; compare the
  // derivative with central differences. Nested Duals must pass through all three.
  auto build = [](auto p, Eigen::Matrix<decltype(p), 3, 3>& A, Eigen::Matrix<decltype(p), 3, 1>& b) {
    using std::cos;
    using std::sin;
    using T = decltype(p);
    A << 4.0 + p, sin(p), 0.5, sin(p), 3.0, p * p, 0.5, p * p, 2.0 + cos(p);
    b << 1.0, p, T(2.0);
  };
  auto solve_all = [&](auto p) {
    using T = decltype(p);
    Eigen::Matrix<T, 3, 3> A;
    Eigen::Matrix<T, 3, 1> b;
    build(p, A, b);
    Eigen::Matrix<T, 3, 1> x1 = A.llt().solve(b);
    Eigen::Matrix<T, 3, 1> x2 = A.partialPivLu().solve(b);
    Eigen::Matrix<T, 3, 1> x3 = Eigen::CompleteOrthogonalDecomposition<Eigen::Matrix<T, 3, 3>>(A).solve(b);
    return std::array<Eigen::Matrix<T, 3, 1>, 3>{x1, x2, x3};
  };
  const double p0 = 0.37, h = 1e-6;
  const auto xd = solve_all(D1(p0, 0));
  const auto xp = solve_all(p0 + h);
  const auto xm = solve_all(p0 - h);
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) {
      const double fd = (xp[k][i] - xm[k][i]) / (2 * h);
      EXPECT_NEAR(xd[k][i].v[0], fd, 1e-8) << "decomposition " << k << " entry " << i;
    }
  // Second order: nested dual through the complete orthogonal decomposition.
  using D2 = Dual<D1, 1>;
  const auto x2 = solve_all(D2(D1(p0, 0), D2::Gradient::Constant(D1(1.0))));
  const auto xdp = solve_all(D1(p0 + h, 0));
  const auto xdm = solve_all(D1(p0 - h, 0));
  for (int i = 0; i < 3; ++i) {
    const double fd2 = (xdp[2][i].v[0] - xdm[2][i].v[0]) / (2 * h);
    EXPECT_NEAR(x2[2][i].v[0].v[0], fd2, 1e-7) << "second derivative, entry " << i;
  }
}

TEST(Dual, ComparisonsUseValuesAndConstantsMixAtEveryLevel) {
  using D2 = Dual<Dual<double, 3>, 2>;
  const D2 x(Dual<double, 3>(0.25, 1), 0);
  EXPECT_TRUE(x < 0.5);
  EXPECT_TRUE(0.1 < x);
  EXPECT_TRUE(x >= 0.25);
  const D2 y = 2 * x + 1.0 - x / 4.0;
  EXPECT_DOUBLE_EQ(saltus::ad::value_of(y), 2 * 0.25 + 1.0 - 0.25 / 4.0);
  EXPECT_TRUE(isfinite(y));
}

}  // namespace
