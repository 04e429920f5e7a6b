// The MPCC solver (timefreezing/mpcc/solve.hpp): a plain NLP (HS071) to its known optimum; a
// small MPCC with a unique B-stationary point, through single-variable and affine sides, with the
// Scholtes relaxation and with the penalty; Ipopt's derivative checker on a nonlinear problem
// with pairs and repeated structure entries, and on deliberately wrong derivatives; an infeasible
// problem reported, not thrown; bad problem statements refused by name; warm against cold starts.
#include <saltus/hybrid/vocabulary/errors.hpp>
#include <saltus/timefreezing/mpcc/mpcc_solver.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>

namespace saltus::timefreezing {
namespace {

constexpr double inf = std::numeric_limits<double>::infinity();

AffineExpression variable(int i) { return AffineExpression{{{i, 1.0}}, 0.0}; }

/// The lower triangle of an n x n matrix, row by row: entry (r, c) has index r (r + 1) / 2 + c.
std::vector<SparseEntry> dense_lower(int n) {
  std::vector<SparseEntry> s;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c <= r; ++c) s.push_back({r, c});
  return s;
}
int lower_index(int r, int c) { return r * (r + 1) / 2 + c; }

void print_steps(const std::string& title, const MpccSolution& s) {
  std::cout << title << ": " << s.message << "\n";
  for (const MpccHomotopyStep& st : s.steps)
    std::cout << "  step " << st.index << (st.retry ? " retry " + std::to_string(st.retry) : std::string())
              << "  sigma " << st.sigma << "  compl " << st.complementarity << "  iter " << st.ipopt_iterations
              << "  " << st.ipopt_status << "  " << st.seconds << " s\n";
  std::cout << "  total: " << s.ipopt_iterations << " Ipopt iterations, " << s.seconds << " s\n";
}

// ---- HS071 (Hock & Schittkowski 71): min x0 x3 (x0 + x1 + x2) + x2
//      s.t. x0 x1 x2 x3 >= 25, |x|^2 = 40, 1 <= x <= 5; from (1, 5, 5, 1).
class Hs071 : public Mpcc {
 public:
  int variable_count() const override { return 4; }
  int constraint_count() const override { return 2; }
  void bounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu, Eigen::Ref<Eigen::VectorXd> gl,
              Eigen::Ref<Eigen::VectorXd> gu) const override {
    xl.setConstant(1.0);
    xu.setConstant(5.0);
    gl << 25.0, 40.0;
    gu << inf, 40.0;
  }
  void initial_point(Eigen::Ref<Eigen::VectorXd> x) const override { x << 1.0, 5.0, 5.0, 1.0; }
  double objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    return x[0] * x[3] * (x[0] + x[1] + x[2]) + x[2];
  }
  void objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> d) const override {
    d << x[3] * (2 * x[0] + x[1] + x[2]), x[0] * x[3], x[0] * x[3] + 1.0, x[0] * (x[0] + x[1] + x[2]);
  }
  void constraints(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const override {
    g << x.prod(), x.squaredNorm();
  }
  const std::vector<SparseEntry>& jacobian_structure() const override { return jac_; }
  void jacobian_values(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> v) const override {
    v << x[1] * x[2] * x[3], x[0] * x[2] * x[3], x[0] * x[1] * x[3], x[0] * x[1] * x[2], 2 * x[0], 2 * x[1],
        2 * x[2], 2 * x[3];
  }
  const std::vector<SparseEntry>& hessian_structure() const override { return hess_; }
  void hessian_values(const Eigen::Ref<const Eigen::VectorXd>& x, double s, const Eigen::Ref<const Eigen::VectorXd>& l,
                      Eigen::Ref<Eigen::VectorXd> v) const override {
    v.setZero();
    auto h = [&v](int r, int c) -> double& { return v[lower_index(r, c)]; };
    h(0, 0) += s * 2 * x[3];
    h(1, 0) += s * x[3];
    h(2, 0) += s * x[3];
    h(3, 0) += s * (2 * x[0] + x[1] + x[2]);
    h(3, 1) += s * x[0];
    h(3, 2) += s * x[0];
    h(1, 0) += l[0] * x[2] * x[3];
    h(2, 0) += l[0] * x[1] * x[3];
    h(3, 0) += l[0] * x[1] * x[2];
    h(2, 1) += l[0] * x[0] * x[3];
    h(3, 1) += l[0] * x[0] * x[2];
    h(3, 2) += l[0] * x[0] * x[1];
    for (int i = 0; i < 4; ++i) h(i, i) += l[1] * 2.0;
  }
  const std::vector<ComplementarityPair>& complementarity_pairs() const override { return pairs_; }

 private:
  std::vector<SparseEntry> jac_{{0, 0}, {0, 1}, {0, 2}, {0, 3}, {1, 0}, {1, 1}, {1, 2}, {1, 3}};
  std::vector<SparseEntry> hess_ = dense_lower(4);
  std::vector<ComplementarityPair> pairs_;
};

// ---- A small MPCC with a unique B-stationary point (0, 2, 0, 2), f = 5:
//   min (x - 1)^2 + (y - 2)^2 + u^2 + (v - 4)^2
//   s.t. x - y <= 0,  x >= 0,
//        0 <= x  _|_  y >= 0                    (x: single variable with bound 0, no row;
//                                                y: single variable without bound, a row)
//        0 <= u + v - 1  _|_  2 - v >= 0        (affine sides, rows)
// Pair 1: on the branch x = 0, y = 2 (f = 1) is a minimum; the branch y = 0 forces x <= 0, and
// its only point (0, 0) is not B-stationary (f decreases along x = 0, y > 0). At the solution
// the objective pulls x away from zero, so its Scholtes relaxation is active (x y = sigma) and
// the residual falls with sigma: 10 steps to 1e-9. Pair 2: on the branch v = 2, u = 0 (f = 4);
// on the branch u + v = 1, v <= 2 the minimum is the corner (-1, 2) (the projection of (0, 4)
// onto the line has v = 2.5), where f decreases along v = 2, u > -1: not B-stationary, and not
// even C-stationary (grad f = (-2, -4) = mu_G (1, 1) + mu_H (0, -1) gives mu_G mu_H = -4 < 0),
// so the relaxations have no reason to stop there. (A first version killed that branch with a
// constraint u + 2 v >= 3 instead; its corner then was C-stationary and the penalty homotopy
// converged to it, f = 6: uniqueness of the B-stationary point alone is not enough.)
class SmallMpcc : public Mpcc {
 public:
  int variable_count() const override { return 4; }
  int constraint_count() const override { return 1; }
  void bounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu, Eigen::Ref<Eigen::VectorXd> gl,
              Eigen::Ref<Eigen::VectorXd> gu) const override {
    xl << 0.0, -inf, -inf, -inf;
    xu.setConstant(inf);
    gl << -inf;
    gu << 0.0;
  }
  void initial_point(Eigen::Ref<Eigen::VectorXd> x) const override { x << 0.5, 1.0, 0.5, 1.0; }
  double objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    return (x - target()).squaredNorm();
  }
  void objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> d) const override {
    d = 2.0 * (x - target());
  }
  void constraints(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const override {
    g << x[0] - x[1];
  }
  const std::vector<SparseEntry>& jacobian_structure() const override { return jac_; }
  void jacobian_values(const Eigen::Ref<const Eigen::VectorXd>&, Eigen::Ref<Eigen::VectorXd> v) const override {
    v << 1.0, -1.0;
  }
  const std::vector<SparseEntry>& hessian_structure() const override { return hess_; }
  void hessian_values(const Eigen::Ref<const Eigen::VectorXd>&, double s, const Eigen::Ref<const Eigen::VectorXd>&,
                      Eigen::Ref<Eigen::VectorXd> v) const override {
    v.setConstant(2.0 * s);
  }
  const std::vector<ComplementarityPair>& complementarity_pairs() const override { return pairs_; }
  std::string variable_name(int i) const override { return std::string(1, "xyuv"[i]); }

  static Eigen::Vector4d target() { return {1.0, 2.0, 0.0, 4.0}; }
  static Eigen::Vector4d solution() { return {0.0, 2.0, 0.0, 2.0}; }

 private:
  std::vector<SparseEntry> jac_{{0, 0}, {0, 1}};
  std::vector<SparseEntry> hess_{{0, 0}, {1, 1}, {2, 2}, {3, 3}};
  std::vector<ComplementarityPair> pairs_{
      {variable(0), variable(1), "x _|_ y"},
      {AffineExpression{{{2, 1.0}, {3, 1.0}}, -1.0}, AffineExpression{{{3, -1.0}}, 2.0}, "u + v - 1 _|_ 2 - v"}};
};

// ---- Nonlinear f and g with pairs, for the derivative checker. The structures repeat
// positions on purpose (g0's d/dx3 listed twice, and the Hessians of f, g0 and g1 listed one
// after the other, overlapping), and one pair has x1 in both sides (a diagonal Hessian entry
// 2 a_G a_H).
//   f  = exp(0.3 x0) x1^2 + x2 x3^3 + sin(x0 x2)
//   g0 = x0 x1 x2 + x3^2,   g1 = cos(x1) + x0^2 x3
//   pairs: x0 _|_ x1 + 2 x2 - 1;   x1 - x3 + 0.5 _|_ 3 - x2 + 0.5 x0 + 2 x1
class NonlinearMpcc : public Mpcc {
 public:
  int variable_count() const override { return 4; }
  int constraint_count() const override { return 2; }
  void bounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu, Eigen::Ref<Eigen::VectorXd> gl,
              Eigen::Ref<Eigen::VectorXd> gu) const override {
    xl << 0.0, -inf, -inf, -inf;
    xu << 10.0, inf, inf, inf;
    gl << -inf, -5.0;
    gu << 4.0, 5.0;
  }
  void initial_point(Eigen::Ref<Eigen::VectorXd> x) const override { x << 0.7, 1.3, 0.4, -0.6; }
  double objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    return std::exp(0.3 * x[0]) * x[1] * x[1] + x[2] * std::pow(x[3], 3) + std::sin(x[0] * x[2]);
  }
  void objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> d) const override {
    const double e = std::exp(0.3 * x[0]), c = std::cos(x[0] * x[2]);
    d << 0.3 * e * x[1] * x[1] + x[2] * c, 2 * e * x[1], std::pow(x[3], 3) + x[0] * c, 3 * x[2] * x[3] * x[3];
  }
  void constraints(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const override {
    g << x[0] * x[1] * x[2] + x[3] * x[3], std::cos(x[1]) + x[0] * x[0] * x[3];
  }
  const std::vector<SparseEntry>& jacobian_structure() const override { return jac_; }
  void jacobian_values(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> v) const override {
    v << x[1] * x[2], x[0] * x[2], x[0] * x[1], x[3], x[3],  // g0 (d/dx3 = 2 x3 in two halves)
        2 * x[0] * x[3], -std::sin(x[1]), x[0] * x[0];       // g1
  }
  const std::vector<SparseEntry>& hessian_structure() const override { return hess_; }
  void hessian_values(const Eigen::Ref<const Eigen::VectorXd>& x, double s, const Eigen::Ref<const Eigen::VectorXd>& l,
                      Eigen::Ref<Eigen::VectorXd> v) const override {
    const double e = std::exp(0.3 * x[0]), p = x[0] * x[2], sn = std::sin(p), c = std::cos(p);
    v << s * (0.09 * e * x[1] * x[1] - x[2] * x[2] * sn), s * 0.6 * e * x[1], s * 2 * e, s * (c - p * sn),
        s * (-x[0] * x[0] * sn), s * 3 * x[3] * x[3], s * 6 * x[2] * x[3],  // f
        l[0] * x[2], l[0] * x[1], l[0] * x[0], l[0] * 2.0,                  // g0
        l[1] * 2 * x[3], l[1] * (-std::cos(x[1])), l[1] * 2 * x[0];          // g1
  }
  const std::vector<ComplementarityPair>& complementarity_pairs() const override { return pairs_; }

 private:
  std::vector<SparseEntry> jac_{{0, 0}, {0, 1}, {0, 2}, {0, 3}, {0, 3}, {1, 0}, {1, 1}, {1, 3}};
  std::vector<SparseEntry> hess_{{0, 0}, {1, 0}, {1, 1}, {2, 0}, {2, 2}, {3, 2}, {3, 3},  // f
                                 {1, 0}, {2, 0}, {2, 1}, {3, 3},                          // g0
                                 {0, 0}, {1, 1}, {3, 0}};                                 // g1
  std::vector<ComplementarityPair> pairs_{
      {variable(0), AffineExpression{{{1, 1.0}, {2, 2.0}}, -1.0}, "x0 _|_ x1 + 2 x2 - 1"},
      {AffineExpression{{{1, 1.0}, {3, -1.0}}, 0.5}, AffineExpression{{{2, -1.0}, {0, 0.5}, {1, 2.0}}, 3.0},
       "x1 - x3 + 0.5 _|_ 3 - x2 + 0.5 x0 + 2 x1"}};
};

/// Forwards everything to a problem; subclasses change one thing.
class Wrapper : public Mpcc {
 public:
  explicit Wrapper(const Mpcc& inner) : inner_(inner) {}
  int variable_count() const override { return inner_.variable_count(); }
  int constraint_count() const override { return inner_.constraint_count(); }
  void bounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu, Eigen::Ref<Eigen::VectorXd> gl,
              Eigen::Ref<Eigen::VectorXd> gu) const override {
    inner_.bounds(xl, xu, gl, gu);
  }
  void initial_point(Eigen::Ref<Eigen::VectorXd> x) const override { inner_.initial_point(x); }
  double objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override { return inner_.objective(x); }
  void objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> d) const override {
    inner_.objective_gradient(x, d);
  }
  void constraints(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const override {
    inner_.constraints(x, g);
  }
  const std::vector<SparseEntry>& jacobian_structure() const override { return inner_.jacobian_structure(); }
  void jacobian_values(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> v) const override {
    inner_.jacobian_values(x, v);
  }
  const std::vector<SparseEntry>& hessian_structure() const override { return inner_.hessian_structure(); }
  void hessian_values(const Eigen::Ref<const Eigen::VectorXd>& x, double s, const Eigen::Ref<const Eigen::VectorXd>& l,
                      Eigen::Ref<Eigen::VectorXd> v) const override {
    inner_.hessian_values(x, s, l, v);
  }
  const std::vector<ComplementarityPair>& complementarity_pairs() const override {
    return inner_.complementarity_pairs();
  }

 protected:
  const Mpcc& inner_;
};

/// One Jacobian or Hessian value off by 0.5.
class WrongDerivative : public Wrapper {
 public:
  enum class Where { Jacobian, Hessian };
  WrongDerivative(const Mpcc& inner, Where where, int entry) : Wrapper(inner), where_(where), entry_(entry) {}
  void jacobian_values(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> v) const override {
    inner_.jacobian_values(x, v);
    if (where_ == Where::Jacobian) v[entry_] += 0.5;
  }
  void hessian_values(const Eigen::Ref<const Eigen::VectorXd>& x, double s, const Eigen::Ref<const Eigen::VectorXd>& l,
                      Eigen::Ref<Eigen::VectorXd> v) const override {
    inner_.hessian_values(x, s, l, v);
    if (where_ == Where::Hessian) v[entry_] += 0.5;
  }

 private:
  Where where_;
  int entry_;
};

int count_lines(const std::string& text) {
  int lines = 0;
  for (char c : text) lines += c == '\n';
  return lines;
}

TEST(MpccSolver, PlainNlpHs071ReachesTheKnownOptimum) {
  Hs071 problem;
  testing::internal::CaptureStdout();
  const MpccSolution s = solve_mpcc(problem);
  const std::string printed = testing::internal::GetCapturedStdout();
  print_steps("HS071", s);
  // print_level 0: not even Ipopt's banner.
  EXPECT_EQ(printed, "");
  ASSERT_TRUE(s.converged) << s.message;
  ASSERT_EQ(s.steps.size(), 1u);  // no pairs: residual 0 after the first solve
  EXPECT_EQ(s.steps[0].ipopt_status, "Solve_Succeeded");
  // Reference: the KKT system at the solution (x0 = 1 on its bound, both constraints active:
  // 3 stationarity rows, 2 constraints, unknowns x1..x3 and the 2 multipliers) solved by Newton's
  // method in 30-digit arithmetic (mpmath), residual 1e-30. Ipopt's documentation prints only
  // 9 digits of it.
  const Eigen::Vector4d x_ref(1.0, 4.7429996372644171, 3.8211499841848739, 1.3794082931726724);
  const double f_ref = 17.014017289156302;
  std::cout << "  x - x_ref = " << (s.x - x_ref).transpose() << ", f = " << s.objective << "\n";
  EXPECT_LE((s.x - x_ref).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_NEAR(s.objective, f_ref, 1e-8);
  EXPECT_LE(s.constraint_violation, 1e-8);
  EXPECT_EQ(s.complementarity, 0.0);
  EXPECT_EQ(s.worst_pair, "");
  ASSERT_EQ(s.constraint_multipliers.size(), 2);
  ASSERT_EQ(s.bound_multipliers_lower.size(), 4);
  // x0 sits on its lower bound 1: its bound multiplier is positive, the others vanish.
  EXPECT_GT(s.bound_multipliers_lower[0], 1e-3);
  EXPECT_LE(s.bound_multipliers_lower.tail(3).cwiseAbs().maxCoeff(), 1e-6);
  // Stationarity of the Lagrangian with the returned multipliers (Ipopt's sign convention).
  Eigen::Vector4d grad;
  problem.objective_gradient(s.x, grad);
  Eigen::VectorXd jv(8);
  problem.jacobian_values(s.x, jv);
  Eigen::Matrix<double, 2, 4> J;
  J << jv.head(4).transpose(), jv.tail(4).transpose();
  const Eigen::Vector4d residual =
      grad + J.transpose() * s.constraint_multipliers - s.bound_multipliers_lower + s.bound_multipliers_upper;
  EXPECT_LE(residual.cwiseAbs().maxCoeff(), 1e-7) << residual.transpose();
}

void expect_small_mpcc_solved(const MpccSolution& s, const std::string& progress) {
  ASSERT_TRUE(s.converged) << s.message;
  EXPECT_LE(s.complementarity, 1e-9);
  EXPECT_LE((s.x - SmallMpcc::solution()).cwiseAbs().maxCoeff(), 1e-7) << s.x.transpose();
  EXPECT_NEAR(s.objective, 5.0, 1e-7);
  EXPECT_LE(s.constraint_violation, 1e-9);
  EXPECT_TRUE(s.steps.back().ipopt_succeeded);
  EXPECT_LE(s.steps.back().complementarity, 1e-9);
  for (std::size_t k = 0; k + 1 < s.steps.size(); ++k) EXPECT_GT(s.steps[k].complementarity, 1e-9);
  EXPECT_EQ(count_lines(progress), static_cast<int>(s.steps.size())) << progress;
  int total = 0;
  for (const MpccHomotopyStep& st : s.steps) total += st.ipopt_iterations;
  EXPECT_EQ(total, s.ipopt_iterations);
  EXPECT_TRUE(s.worst_pair == "x _|_ y" || s.worst_pair == "u + v - 1 _|_ 2 - v") << s.worst_pair;
  EXPECT_EQ(s.constraint_multipliers.size(), 1);
}

TEST(MpccSolver, ScholtesReachesTheUniqueBStationaryPoint) {
  SmallMpcc problem;
  std::ostringstream progress;
  MpccSolverOptions options;
  options.progress = &progress;
  options.polish.enabled = false;  // the homotopy alone (PolishingMakesSmallMpccExactlyComplementary)
  const MpccSolution s = solve_mpcc(problem, options);
  print_steps("SmallMpcc, Scholtes", s);
  std::cout << progress.str();
  expect_small_mpcc_solved(s, progress.str());
  // The relaxation is active: the residual follows sigma (x y = sigma at the relaxed solution, up
  // to Ipopt's tolerance on the row x y <= sigma, which can leave it a few 1e-12 above sigma), so
  // it takes sigma = 1e-9 or 1e-10: the 10th or 11th step.
  EXPECT_GE(s.steps.size(), 10u);
  EXPECT_LE(s.steps.size(), 11u);
  EXPECT_NEAR(s.steps[0].complementarity, 1.0, 1e-6);
  EXPECT_EQ(s.worst_pair, "x _|_ y");
  EXPECT_NE(progress.str().find("Solve_Succeeded"), std::string::npos);
  EXPECT_NE(progress.str().find("sigma"), std::string::npos);
}

// Refinement past convergence (MpccSolverOptions::Homotopy::complementarity_refinement): on
// SmallMpcc the Scholtes row of x _|_ y is active (x y = sigma, x = sigma / 2), so the converged homotopy's x is
// ~1e-10 from the solution; refined, the homotopy goes on decreasing sigma until the residual is at
// the target or stops falling, and x follows it. A successful polish leaves nothing to refine.
TEST(MpccSolver, RefinementGoesOnPastConvergence) {
  SmallMpcc problem;
  MpccSolverOptions options;
  options.polish.enabled = false;
  const MpccSolution plain = solve_mpcc(problem, options);
  options.homotopy.complementarity_refinement = 1e-13;
  std::ostringstream progress;
  options.progress = &progress;
  const MpccSolution refined = solve_mpcc(problem, options);
  print_steps("SmallMpcc, Scholtes, refined to 1e-13", refined);
  std::cout << refined.message << "\n";
  ASSERT_TRUE(plain.converged) << plain.message;
  ASSERT_TRUE(refined.converged) << refined.message;
  EXPECT_GT(refined.steps.size(), plain.steps.size() + 1);
  EXPECT_EQ(count_lines(progress.str()), static_cast<int>(refined.steps.size())) << "one line per step";
  EXPECT_LE(refined.complementarity, 1e-3 * plain.complementarity);
  const double error_plain = (plain.x - SmallMpcc::solution()).cwiseAbs().maxCoeff();
  const double error_refined = (refined.x - SmallMpcc::solution()).cwiseAbs().maxCoeff();
  std::printf("x error: converged %.2e, refined %.2e; residual %.2e -> %.2e\n", error_plain, error_refined,
              plain.complementarity, refined.complementarity);
  EXPECT_LE(error_refined, 1e-2 * error_plain);  // x follows sigma; the other unknowns sit at Ipopt's tol
  // The accepted refinement steps lower the residual; the returned point is the last of them.
  double previous = INFINITY;
  int accepted = 0;
  for (const MpccHomotopyStep& st : refined.steps) {
    if (!st.ipopt_succeeded || st.complementarity >= previous) continue;
    previous = st.complementarity;
    ++accepted;
  }
  EXPECT_EQ(previous, refined.complementarity);
  EXPECT_GE(accepted, static_cast<int>(plain.steps.size()) + 2);
  EXPECT_NE(refined.message.find("refinement steps accepted"), std::string::npos) << refined.message;

  // A target out of reach: the refinement ends on a step that fails, does not lower the residual,
  // or exhausts max_homotopy_steps, and the result is the last accepted step, still converged.
  options.homotopy.complementarity_refinement = 1e-30;
  options.progress = nullptr;
  const MpccSolution unreachable = solve_mpcc(problem, options);
  std::cout << unreachable.message << "\n";
  ASSERT_TRUE(unreachable.converged) << unreachable.message;
  EXPECT_LE(unreachable.complementarity, refined.complementarity);
  const bool ended = unreachable.message.find("refinement ended") != std::string::npos ||
                     unreachable.message.find("refinement stopped by homotopy.max_steps") != std::string::npos;
  EXPECT_TRUE(ended) << unreachable.message;
  EXPECT_LE(unreachable.constraint_violation, 1e-8);

  // With the default polish (exact on SmallMpcc) there is nothing left to refine.
  MpccSolverOptions polished;
  const MpccSolution p0 = solve_mpcc(problem, polished);
  polished.homotopy.complementarity_refinement = 1e-13;
  const MpccSolution p1 = solve_mpcc(problem, polished);
  ASSERT_TRUE(p1.converged && p1.polished) << p1.message;
  EXPECT_EQ(p1.steps.size(), p0.steps.size());
}

TEST(MpccSolver, PenaltyReachesTheUniqueBStationaryPoint) {
  SmallMpcc problem;
  std::ostringstream progress;
  MpccSolverOptions options;
  options.homotopy.relaxation = MpccSolverOptions::Relaxation::Penalty;
  options.progress = &progress;
  options.polish.enabled = false;
  const MpccSolution s = solve_mpcc(problem, options);
  print_steps("SmallMpcc, Penalty", s);
  std::cout << progress.str();
  expect_small_mpcc_solved(s, progress.str());
  // The penalty is exact once rho exceeds the multipliers (rho > 1 here): few steps.
  EXPECT_LE(s.steps.size(), 4u);
  EXPECT_NE(progress.str().find("rho"), std::string::npos);
}

// ---- min (x - 2)^2 + y^2  s.t.  0 <= x _|_ y >= 0: solution (2, 0), where the objective pulls y
// to the bound, so the Scholtes row x y <= sigma is INACTIVE (x y = 0 at every relaxed solution);
// the smoothing equality x y = sigma holds the pair on its curve, y = sigma / x -> sigma / 2.
class InactivePair : public Mpcc {
 public:
  explicit InactivePair(bool smoothable) { pairs_[0].smoothable = smoothable; }
  int variable_count() const override { return 2; }
  int constraint_count() const override { return 0; }
  void bounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu, Eigen::Ref<Eigen::VectorXd>,
              Eigen::Ref<Eigen::VectorXd>) const override {
    xl.setZero();
    xu.setConstant(inf);
  }
  void initial_point(Eigen::Ref<Eigen::VectorXd> x) const override { x << 1.0, 1.0; }
  double objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    return (x[0] - 2.0) * (x[0] - 2.0) + x[1] * x[1];
  }
  void objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> d) const override {
    d << 2.0 * (x[0] - 2.0), 2.0 * x[1];
  }
  void constraints(const Eigen::Ref<const Eigen::VectorXd>&, Eigen::Ref<Eigen::VectorXd>) const override {}
  const std::vector<SparseEntry>& jacobian_structure() const override { return jac_; }
  void jacobian_values(const Eigen::Ref<const Eigen::VectorXd>&, Eigen::Ref<Eigen::VectorXd>) const override {}
  const std::vector<SparseEntry>& hessian_structure() const override { return hess_; }
  void hessian_values(const Eigen::Ref<const Eigen::VectorXd>&, double s, const Eigen::Ref<const Eigen::VectorXd>&,
                      Eigen::Ref<Eigen::VectorXd> v) const override {
    v.setConstant(2.0 * s);
  }
  const std::vector<ComplementarityPair>& complementarity_pairs() const override { return pairs_; }

 private:
  std::vector<SparseEntry> jac_;
  std::vector<SparseEntry> hess_{{0, 0}, {1, 1}};
  std::vector<ComplementarityPair> pairs_{{variable(0), variable(1), "x _|_ y"}};
};

// Relaxation::Smoothing puts a smoothable pair on its curve G H = sigma_k at every step; an
// unmarked pair (and every pair under Scholtes) keeps the inequality, inactive here.
TEST(MpccSolver, SmoothingHoldsASmoothablePairOnItsCurve) {
  MpccSolverOptions options;
  options.polish.enabled = false;
  options.homotopy.relaxation = MpccSolverOptions::Relaxation::Smoothing;
  const InactivePair marked(true), unmarked(false);
  for (int steps = 1; steps <= 4; ++steps) {
    options.homotopy.max_steps = steps;
    const MpccSolution s = solve_mpcc(marked, options);
    const double sigma = s.steps.back().sigma;
    EXPECT_NEAR(s.x[0] * s.x[1], sigma, 1e-8 * sigma) << "step " << steps;
    EXPECT_NEAR(s.x[1], sigma / s.x[0], 1e-8 * sigma);
    // The inactive inequality leaves the product at Ipopt's tolerance level (about 1e-5 here).
    if (steps <= 2) {
      EXPECT_LT(solve_mpcc(unmarked, options).complementarity, 1e-2 * sigma) << "step " << steps;
    }
  }
  options.homotopy.max_steps = 30;
  const MpccSolution smoothed = solve_mpcc(marked, options);
  ASSERT_TRUE(smoothed.converged) << smoothed.message;
  EXPECT_EQ(smoothed.smoothed_pairs, 1);
  EXPECT_EQ(solve_mpcc(unmarked, options).smoothed_pairs, 0);
  // sigma_k = 1, 0.1, ..., 1e-9 exactly (decades snapped): the residual IS sigma_k, so the 10th
  // step meets the tolerance 1e-9 (a drifting product 1.0000000000000005e-9 would take an 11th).
  EXPECT_EQ(smoothed.steps.size(), 10u);
  EXPECT_EQ(smoothed.steps.back().sigma, 1e-9);
  EXPECT_NEAR(smoothed.x[0], 2.0, 1e-8);
  EXPECT_GT(smoothed.x[1], 0.0);
  EXPECT_LE(smoothed.complementarity, 1e-9);
  options.homotopy.relaxation = MpccSolverOptions::Relaxation::Scholtes;
  options.homotopy.max_steps = 2;
  EXPECT_LT(solve_mpcc(marked, options).complementarity, 1e-3);  // sigma = 0.1
}

TEST(MpccSolver, StartsFromAGivenPointAndMultipliers) {
  SmallMpcc problem;
  const MpccSolution first = solve_mpcc(problem);
  ASSERT_TRUE(first.converged) << first.message;
  MpccStart start{first.x, first.constraint_multipliers, first.bound_multipliers_lower, first.bound_multipliers_upper};
  MpccSolverOptions options;
  options.homotopy.sigma_0 = 1e-9;  // at the end of the homotopy already: one step from the solution
  options.polish.enabled = false;
  const MpccSolution again = solve_mpcc(problem, start, options);
  print_steps("SmallMpcc from its solution", again);
  ASSERT_TRUE(again.converged) << again.message;
  EXPECT_EQ(again.steps.size(), 1u);
  EXPECT_LE((again.x - SmallMpcc::solution()).cwiseAbs().maxCoeff(), 1e-7);
  // Wrong sizes are refused.
  start.constraint_multipliers.resize(3);
  EXPECT_THROW(solve_mpcc(problem, start, options), InvalidArgument);
  EXPECT_THROW(solve_mpcc(problem, MpccStart{Eigen::VectorXd::Zero(3), {}, {}, {}}, options), InvalidArgument);
}

TEST(MpccSolver, DerivativeCheckerPassesCorrectDerivatives) {
  NonlinearMpcc problem;
  Eigen::VectorXd x(4);
  problem.initial_point(x);
  const DerivativeCheckReport report = check_derivatives(problem, x);
  std::cout << "derivative check (correct): " << report.errors << " errors, status " << report.ipopt_status << "\n"
            << report.output;
  EXPECT_EQ(report.errors, 0) << report.output;
  EXPECT_NE(report.output.find("No errors detected by derivative checker"), std::string::npos) << report.output;
  // And the other problems' hand-written derivatives.
  Hs071 hs071;
  Eigen::VectorXd y(4);
  y << 1.5, 4.0, 3.5, 1.2;
  EXPECT_EQ(check_derivatives(hs071, y).errors, 0);
  SmallMpcc small;
  EXPECT_EQ(check_derivatives(small, SmallMpcc::target()).errors, 0);
}

TEST(MpccSolver, DerivativeCheckerFlagsAWrongJacobianOrHessianEntry) {
  NonlinearMpcc problem;
  Eigen::VectorXd x(4);
  problem.initial_point(x);
  // Jacobian entry 4 is the second half of d g0 / d x3 (a repeated position); Hessian entry 9
  // is g0's (2, 1).
  const WrongDerivative wrong_jacobian(problem, WrongDerivative::Where::Jacobian, 4);
  const DerivativeCheckReport j = check_derivatives(wrong_jacobian, x);
  std::cout << "derivative check (wrong Jacobian): " << j.errors << " errors\n" << j.output;
  EXPECT_GT(j.errors, 0);
  EXPECT_NE(j.output.find("jac_g"), std::string::npos) << j.output;
  const WrongDerivative wrong_hessian(problem, WrongDerivative::Where::Hessian, 9);
  const DerivativeCheckReport h = check_derivatives(wrong_hessian, x);
  std::cout << "derivative check (wrong Hessian): " << h.errors << " errors\n" << h.output;
  EXPECT_GT(h.errors, 0);
  EXPECT_NE(h.output.find("Derivative checker detected"), std::string::npos) << h.output;
}

// min x^2 + y^2 s.t. x^2 + y^2 <= 1, x + y >= 3, 0 <= x _|_ y >= 0: no feasible point.
class Infeasible : public Mpcc {
 public:
  int variable_count() const override { return 2; }
  int constraint_count() const override { return 2; }
  void bounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu, Eigen::Ref<Eigen::VectorXd> gl,
              Eigen::Ref<Eigen::VectorXd> gu) const override {
    xl.setZero();
    xu.setConstant(inf);
    gl << -inf, 3.0;
    gu << 1.0, inf;
  }
  void initial_point(Eigen::Ref<Eigen::VectorXd> x) const override { x << 0.5, 0.5; }
  double objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override { return x.squaredNorm(); }
  void objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> d) const override {
    d = 2 * x;
  }
  void constraints(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const override {
    g << x.squaredNorm(), x.sum();
  }
  const std::vector<SparseEntry>& jacobian_structure() const override { return jac_; }
  void jacobian_values(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> v) const override {
    v << 2 * x[0], 2 * x[1], 1.0, 1.0;
  }
  const std::vector<SparseEntry>& hessian_structure() const override { return hess_; }
  void hessian_values(const Eigen::Ref<const Eigen::VectorXd>&, double s, const Eigen::Ref<const Eigen::VectorXd>& l,
                      Eigen::Ref<Eigen::VectorXd> v) const override {
    v.setConstant(2 * s + 2 * l[0]);
  }
  const std::vector<ComplementarityPair>& complementarity_pairs() const override { return pairs_; }
  std::string constraint_name(int j) const override { return j == 0 ? "x^2 + y^2 <= 1" : "x + y >= 3"; }

 private:
  std::vector<SparseEntry> jac_{{0, 0}, {0, 1}, {1, 0}, {1, 1}};
  std::vector<SparseEntry> hess_{{0, 0}, {1, 1}};
  std::vector<ComplementarityPair> pairs_{{variable(0), variable(1), "x _|_ y"}};
};

TEST(MpccSolver, InfeasibleProblemIsReportedNotThrown) {
  Infeasible problem;
  std::ostringstream progress;
  MpccSolverOptions options;
  options.progress = &progress;
  MpccSolution s;
  ASSERT_NO_THROW(s = solve_mpcc(problem, options));
  print_steps("Infeasible", s);
  std::cout << progress.str();
  EXPECT_FALSE(s.converged);
  ASSERT_FALSE(s.steps.empty());
  EXPECT_FALSE(s.steps.back().ipopt_succeeded);
  EXPECT_NE(s.steps.back().ipopt_status.find("Infeasible"), std::string::npos) << s.steps.back().ipopt_status;
  EXPECT_NE(s.message.find("Infeasible_Problem_Detected"), std::string::npos) << s.message;
  EXPECT_GT(s.constraint_violation, 0.1);
  EXPECT_EQ(count_lines(progress.str()), static_cast<int>(s.steps.size()));
  // The failed step names where its iterate is infeasible: one of the two rows, by its name, in
  // the step and in its progress line.
  const std::string& worst = s.steps.back().worst_violation;
  EXPECT_TRUE(worst == "x^2 + y^2 <= 1" || worst == "x + y >= 3") << worst;
  EXPECT_NE(progress.str().find("worst: " + worst), std::string::npos) << progress.str();
}

/// SmallMpcc with one flaw in its statement.
class Flawed : public Wrapper {
 public:
  enum class Flaw { NanStart, CrossedBounds, JacobianOutOfRange, UpperHessian, PairVariableOutOfRange };
  Flawed(const Mpcc& inner, Flaw flaw) : Wrapper(inner), flaw_(flaw) {
    jac_ = inner.jacobian_structure();
    hess_ = inner.hessian_structure();
    pairs_ = inner.complementarity_pairs();
    if (flaw == Flaw::JacobianOutOfRange) jac_[1].col = 7;
    if (flaw == Flaw::UpperHessian) hess_.push_back({0, 3});
    if (flaw == Flaw::PairVariableOutOfRange) pairs_[1].right.terms[0].first = 4;
  }
  void bounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu, Eigen::Ref<Eigen::VectorXd> gl,
              Eigen::Ref<Eigen::VectorXd> gu) const override {
    inner_.bounds(xl, xu, gl, gu);
    if (flaw_ == Flaw::CrossedBounds) {
      xl[2] = 3.0;
      xu[2] = 2.0;
    }
  }
  void initial_point(Eigen::Ref<Eigen::VectorXd> x) const override {
    inner_.initial_point(x);
    if (flaw_ == Flaw::NanStart) x[1] = std::numeric_limits<double>::quiet_NaN();
  }
  const std::vector<SparseEntry>& jacobian_structure() const override { return jac_; }
  const std::vector<SparseEntry>& hessian_structure() const override { return hess_; }
  void hessian_values(const Eigen::Ref<const Eigen::VectorXd>& x, double s, const Eigen::Ref<const Eigen::VectorXd>& l,
                      Eigen::Ref<Eigen::VectorXd> v) const override {
    inner_.hessian_values(x, s, l, v.head(inner_.hessian_structure().size()));
  }
  const std::vector<ComplementarityPair>& complementarity_pairs() const override { return pairs_; }
  std::string variable_name(int i) const override { return inner_.variable_name(i); }

 private:
  Flaw flaw_;
  std::vector<SparseEntry> jac_, hess_;
  std::vector<ComplementarityPair> pairs_;
};

void expect_refused(const Mpcc& problem, const std::vector<std::string>& words) {
  try {
    solve_mpcc(problem);
    ADD_FAILURE() << "no exception";
  } catch (const InvalidArgument& e) {
    const std::string what = e.what();
    std::cout << "refused: " << what << "\n";
    for (const std::string& w : words) EXPECT_NE(what.find(w), std::string::npos) << "'" << w << "' not in: " << what;
  }
}

TEST(MpccSolver, BadProblemStatementsAreRefusedByName) {
  SmallMpcc good;
  expect_refused(Flawed(good, Flawed::Flaw::NanStart), {"initial point", "variable 1", "(y)", "not finite"});
  expect_refused(Flawed(good, Flawed::Flaw::CrossedBounds), {"lower bound > upper bound", "variable 2", "(u)"});
  expect_refused(Flawed(good, Flawed::Flaw::JacobianOutOfRange), {"jacobian_structure() entry 1", "(0, 7)",
                                                                 "out of range"});
  expect_refused(Flawed(good, Flawed::Flaw::UpperHessian), {"hessian_structure() entry 4", "(0, 3)",
                                                           "above the diagonal"});
  expect_refused(Flawed(good, Flawed::Flaw::PairVariableOutOfRange), {"u + v - 1 _|_ 2 - v", "right side",
                                                                     "index 4"});
  // The derivative checker validates the same way.
  EXPECT_THROW(check_derivatives(Flawed(good, Flawed::Flaw::UpperHessian), SmallMpcc::target()), InvalidArgument);
}

TEST(MpccSolver, BadOptionsAreRefusedByName) {
  SmallMpcc problem;
  auto refused = [&](const MpccSolverOptions& options, const std::string& word) {
    try {
      solve_mpcc(problem, options);
      ADD_FAILURE() << "no exception for " << word;
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  MpccSolverOptions o;
  o.homotopy.kappa = 1.0;
  refused(o, "kappa");
  o = {};
  o.homotopy.sigma_0 = 0.0;
  refused(o, "sigma_0");
  o = {};
  o.homotopy.max_steps = 0;
  refused(o, "homotopy.max_steps");
  o = {};
  o.ipopt.options.push_back({"no_such_ipopt_option", 1});
  refused(o, "no_such_ipopt_option");
  o = {};
  o.ipopt.options.push_back({"mu_strategy", std::string("sideways")});
  refused(o, "mu_strategy");
  o = {};
  o.homotopy.complementarity_refinement = 1e-8;  // above complementarity_tolerance
  refused(o, "complementarity_refinement");
  o = {};
  o.homotopy.complementarity_refinement = -1e-12;
  refused(o, "complementarity_refinement");
  o = {};
  o.ipopt.options.push_back({"mumps_mem_percent", -1});
  refused(o, "mumps_mem_percent");
  // A valid extra option is accepted.
  o = {};
  o.ipopt.options.push_back({"acceptable_iter", 10});
  o.ipopt.options.push_back({"mumps_pivtol", 1e-6});
  EXPECT_TRUE(solve_mpcc(problem, o).converged);
}

/// SmallMpcc whose objective turns NaN once `poisoned` is set (by PoisonOnNewline below, at the
/// first progress line): every step after the first then fails with Invalid_Number_Detected.
class PoisonedAfterFirstStep : public Wrapper {
 public:
  using Wrapper::Wrapper;
  double objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    return poisoned ? std::numeric_limits<double>::quiet_NaN() : inner_.objective(x);
  }
  mutable bool poisoned = false;
};

/// Poisons `problem` at the first progress line; with cure_at > 0, cures it again at line cure_at.
class PoisonOnNewline : public std::streambuf {
 public:
  explicit PoisonOnNewline(const PoisonedAfterFirstStep& p, int cure_at = 0) : problem_(p), cure_at_(cure_at) {}
  std::string text;

 protected:
  int overflow(int c) override {
    if (c == '\n') problem_.poisoned = cure_at_ <= 0 || ++lines_ < cure_at_;
    if (c != EOF) text.push_back(static_cast<char>(c));
    return c;
  }

 private:
  const PoisonedAfterFirstStep& problem_;
  int cure_at_ = 0, lines_ = 0;
};

TEST(MpccSolver, FailedStepsAreRetriedWithSlowerDecreaseThenReported) {
  SmallMpcc inner;
  PoisonedAfterFirstStep problem(inner);
  PoisonOnNewline buffer(problem);
  std::ostream progress(&buffer);
  MpccSolverOptions options;
  options.progress = &progress;
  options.polish.enabled = false;
  MpccSolution s;
  ASSERT_NO_THROW(s = solve_mpcc(problem, options));
  print_steps("poisoned after the first step", s);
  std::cout << buffer.text;
  EXPECT_FALSE(s.converged);
  // Step 0, then step 1 and its 3 retries at sigma = kappa' sigma_0, kappa' = 0.1^(1/2, 1/4, 1/8).
  ASSERT_EQ(s.steps.size(), 5u);
  EXPECT_TRUE(s.steps[0].ipopt_succeeded);
  const double expected_sigma[] = {1.0, 0.1, std::pow(0.1, 0.5), std::pow(0.1, 0.25), std::pow(0.1, 0.125)};
  for (int k = 1; k < 5; ++k) {
    EXPECT_EQ(s.steps[k].index, 1);
    EXPECT_EQ(s.steps[k].retry, k - 1);
    EXPECT_FALSE(s.steps[k].ipopt_succeeded);
    EXPECT_EQ(s.steps[k].ipopt_status, "Invalid_Number_Detected");
    EXPECT_NEAR(s.steps[k].sigma, expected_sigma[k], 1e-12);
  }
  EXPECT_NE(s.message.find("after 3 retries"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("Invalid_Number_Detected"), std::string::npos) << s.message;
  // The result is the last successful iterate (step 0's), with its residual.
  EXPECT_NEAR(s.complementarity, s.steps[0].complementarity, 1e-12);
  EXPECT_EQ(count_lines(buffer.text), 5);

  // With polishing, the homotopy's last successful step (step 0) is polished after the failure;
  // the polish fails too (NaN objective), is recorded, and the result stays step 0's.
  PoisonedAfterFirstStep problem2(inner);
  PoisonOnNewline buffer2(problem2);
  std::ostream progress2(&buffer2);
  options.polish.enabled = true;
  options.progress = &progress2;
  MpccSolution p;
  ASSERT_NO_THROW(p = solve_mpcc(problem2, options));
  print_steps("poisoned, with polishing", p);
  std::cout << buffer2.text;
  EXPECT_FALSE(p.converged);
  EXPECT_FALSE(p.polished);
  ASSERT_EQ(p.steps.size(), 6u);
  EXPECT_TRUE(p.steps[5].polish);
  EXPECT_EQ(p.steps[5].index, 0);
  EXPECT_FALSE(p.steps[5].ipopt_succeeded);
  EXPECT_NE(p.steps[5].note.find("Invalid_Number_Detected"), std::string::npos) << p.steps[5].note;
  EXPECT_NE(p.message.find("after 3 retries"), std::string::npos) << p.message;
  EXPECT_EQ(p.x, s.x);
  EXPECT_EQ(count_lines(buffer2.text), 6);
  EXPECT_NE(buffer2.text.find("mpcc polish"), std::string::npos);
}

TEST(MpccSolver, WarmStartNeedsNoMoreIterationsThanColdStarts) {
  SmallMpcc problem;
  MpccSolverOptions warm;
  MpccSolverOptions cold;
  warm.polish.enabled = false;
  cold.polish.enabled = false;
  cold.warm_start = false;
  const MpccSolution w = solve_mpcc(problem, warm);
  const MpccSolution c = solve_mpcc(problem, cold);
  print_steps("warm (primal-dual)", w);
  print_steps("cold (primal only)", c);
  ASSERT_TRUE(w.converged) << w.message;
  ASSERT_TRUE(c.converged) << c.message;
  ASSERT_GE(w.steps.size(), 5u);
  ASSERT_GE(c.steps.size(), 5u);
  std::cout << "total Ipopt iterations: warm " << w.ipopt_iterations << ", cold " << c.ipopt_iterations << "\n";
  EXPECT_LE(w.ipopt_iterations, c.ipopt_iterations);
}

// ---- Polishing (branch NLP) and row pruning

TEST(MpccSolver, PolishingMakesSmallMpccExactlyComplementary) {
  SmallMpcc problem;
  std::ostringstream progress;
  MpccSolverOptions on;
  on.progress = &progress;
  on.polish.below = 1e-6;  // polish early (default: after the last step only)
  MpccSolverOptions off;
  off.polish.enabled = false;
  const MpccSolution p = solve_mpcc(problem, on);
  const MpccSolution h = solve_mpcc(problem, off);
  print_steps("SmallMpcc, polished", p);
  std::cout << progress.str();
  print_steps("SmallMpcc, homotopy only", h);
  std::cout << "total Ipopt iterations: polish " << p.ipopt_iterations << ", homotopy only " << h.ipopt_iterations
            << "\n  polished x = " << p.x.transpose() << "\n  homotopy x = " << h.x.transpose()
            << "\n  z_L = " << p.bound_multipliers_lower.transpose()
            << "\n  z_U = " << p.bound_multipliers_upper.transpose()
            << "\n  lambda = " << p.constraint_multipliers.transpose() << "\n";
  ASSERT_TRUE(p.converged) << p.message;
  ASSERT_TRUE(h.converged) << h.message;
  EXPECT_TRUE(p.polished);
  EXPECT_FALSE(h.polished);
  EXPECT_NE(p.message.find("polished from homotopy step"), std::string::npos) << p.message;
  // The branch fixes x = 0 (x _|_ y: x is the smaller side) and v = 2 (the side 2 - v, one
  // variable): the zero sides are exactly zero, and so is the residual; the homotopy alone only
  // gets to its tolerance (x y ~ sigma: the relaxation is active).
  EXPECT_EQ(p.x[0], 0.0);
  EXPECT_EQ(p.x[3], 2.0);
  EXPECT_EQ(p.complementarity, 0.0);
  EXPECT_GT(h.complementarity, 1e-12);
  EXPECT_GT(h.x[0], 0.0);
  EXPECT_NEAR(p.x[1], 2.0, 1e-9);
  EXPECT_NEAR(p.x[2], 0.0, 1e-9);
  EXPECT_NEAR(p.objective, 5.0, 1e-9);
  EXPECT_LE(p.constraint_violation, 1e-12);
  // The polish is a step of its own, last, after the step whose residual first fell below
  // polish_below = 1e-6; the homotopy stops there, fewer steps and iterations in all.
  ASSERT_GE(p.steps.size(), 2u);
  const MpccHomotopyStep& last = p.steps.back();
  EXPECT_TRUE(last.polish);
  EXPECT_TRUE(last.ipopt_succeeded);
  EXPECT_EQ(last.note, "");
  EXPECT_EQ(last.left_zero, 1);   // x = 0
  EXPECT_EQ(last.right_zero, 1);  // 2 - v = 0
  EXPECT_EQ(last.biactive, 0);
  EXPECT_EQ(last.index, p.steps[p.steps.size() - 2].index);
  EXPECT_LE(p.steps[p.steps.size() - 2].complementarity, on.polish.below);
  for (std::size_t k = 0; k + 1 < p.steps.size(); ++k) EXPECT_FALSE(p.steps[k].polish);
  EXPECT_LT(p.steps.size(), h.steps.size());
  EXPECT_LT(p.ipopt_iterations, h.ipopt_iterations);
  int total = 0;
  for (const MpccHomotopyStep& st : p.steps) total += st.ipopt_iterations;
  EXPECT_EQ(total, p.ipopt_iterations);
  EXPECT_EQ(count_lines(progress.str()), static_cast<int>(p.steps.size()));
  EXPECT_NE(progress.str().find("mpcc polish"), std::string::npos);
  EXPECT_NE(progress.str().find("G=0 1 H=0 1 biactive 0 trend 0"), std::string::npos) << progress.str();

  // By default only the homotopy's last step is polished: the homotopy's own steps, then one
  // polish, still exactly complementary.
  const MpccSolution d = solve_mpcc(problem);
  ASSERT_TRUE(d.converged) << d.message;
  EXPECT_TRUE(d.polished);
  EXPECT_EQ(d.steps.size(), h.steps.size() + 1);
  EXPECT_EQ(d.complementarity, 0.0);
  EXPECT_EQ(d.x[0], 0.0);
  // Multipliers of the ORIGINAL rows (one), and stationarity of the branch NLP's Lagrangian with
  // the bound multipliers Ipopt reports: the fixed x and v carry the pairs' multipliers
  // (grad f = (-2, 0, 0, -4) at the solution; x - y <= 0 is inactive).
  ASSERT_EQ(p.constraint_multipliers.size(), 1);
  ASSERT_EQ(p.bound_multipliers_lower.size(), 4);
  ASSERT_EQ(p.bound_multipliers_upper.size(), 4);
  EXPECT_NEAR(p.constraint_multipliers[0], 0.0, 1e-8);
  Eigen::Vector4d grad;
  problem.objective_gradient(p.x, grad);
  const Eigen::Vector4d residual = grad + Eigen::Vector4d(1.0, -1.0, 0.0, 0.0) * p.constraint_multipliers[0] -
                                   p.bound_multipliers_lower + p.bound_multipliers_upper;
  std::cout << "  stationarity residual with the reported bound multipliers: " << residual.transpose() << "\n";
  EXPECT_LE(residual.cwiseAbs().maxCoeff(), 1e-8) << residual.transpose();
  EXPECT_NEAR(p.bound_multipliers_upper[0], 2.0, 1e-8);  // x's pair: the objective pulls x up
  EXPECT_NEAR(p.bound_multipliers_upper[3], 4.0, 1e-8);  // v's pair: 2 - v = 0 against v -> 4
}

// min (y - 1)^2 + x^2 + w^2  s.t.  x - w >= 0 (or, `by_bound`, x >= 0.01 as a bound, without
// w's row), w >= 0.01, 0 <= x _|_ y >= 0. The solution is y = 0, x = w = 0.01 (f = 1.0002; the
// branch x = 0 is infeasible). The relaxed solutions have x = 0.01 and
// y = min(1, 100 sigma): y is the larger side (the wrong branch: x = 0) until sigma < 1e-4.
class WrongBranchFirst : public Mpcc {
 public:
  explicit WrongBranchFirst(bool by_bound) : by_bound_(by_bound) {}
  int variable_count() const override { return 3; }  // x, y, w
  int constraint_count() const override { return by_bound_ ? 0 : 1; }
  void bounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu, Eigen::Ref<Eigen::VectorXd> gl,
              Eigen::Ref<Eigen::VectorXd> gu) const override {
    xl << (by_bound_ ? 0.01 : 0.0), 0.0, 0.01;
    xu.setConstant(inf);
    if (!by_bound_) {
      gl << 0.0;
      gu << inf;
    }
  }
  void initial_point(Eigen::Ref<Eigen::VectorXd> x) const override { x << 0.5, 0.5, 0.5; }
  double objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    return (x[1] - 1) * (x[1] - 1) + x[0] * x[0] + x[2] * x[2];
  }
  void objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> d) const override {
    d << 2 * x[0], 2 * (x[1] - 1), 2 * x[2];
  }
  void constraints(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const override {
    if (!by_bound_) g << x[0] - x[2];
  }
  const std::vector<SparseEntry>& jacobian_structure() const override { return by_bound_ ? no_jac_ : jac_; }
  void jacobian_values(const Eigen::Ref<const Eigen::VectorXd>&, Eigen::Ref<Eigen::VectorXd> v) const override {
    if (!by_bound_) v << 1.0, -1.0;
  }
  const std::vector<SparseEntry>& hessian_structure() const override { return hess_; }
  void hessian_values(const Eigen::Ref<const Eigen::VectorXd>&, double s, const Eigen::Ref<const Eigen::VectorXd>&,
                      Eigen::Ref<Eigen::VectorXd> v) const override {
    v.setConstant(2.0 * s);
  }
  const std::vector<ComplementarityPair>& complementarity_pairs() const override { return pairs_; }
  std::string variable_name(int i) const override { return std::string(1, "xyw"[i]); }

 private:
  bool by_bound_;
  std::vector<SparseEntry> jac_{{0, 0}, {0, 2}}, no_jac_;
  std::vector<SparseEntry> hess_{{0, 0}, {1, 1}, {2, 2}};
  std::vector<ComplementarityPair> pairs_{{variable(0), variable(1), "x _|_ y"}};
};

TEST(MpccSolver, FailedPolishKeepsTheHomotopyGoing) {
  for (const bool by_bound : {false, true}) {
    WrongBranchFirst problem(by_bound);
    std::ostringstream progress;
    MpccSolverOptions options;
    options.progress = &progress;
    options.polish.below = 10.0;  // polish after every step
    const MpccSolution s = solve_mpcc(problem, options);
    const std::string title = by_bound ? "WrongBranchFirst (bound)" : "WrongBranchFirst (row)";
    print_steps(title, s);
    std::cout << progress.str();
    ASSERT_TRUE(s.converged) << s.message;
    EXPECT_TRUE(s.polished);
    // Steps and polishes alternate; the early polishes pick x = 0 and fail: Ipopt finds the
    // branch infeasible (row x - w >= 0, w >= 0.01), or the bounds already contradict it (x >=
    // 0.01), without a solve.
    int failed = 0;
    for (std::size_t k = 0; k < s.steps.size(); ++k) {
      const MpccHomotopyStep& st = s.steps[k];
      EXPECT_EQ(st.polish, k % 2 == 1) << k;
      if (!st.polish) {
        EXPECT_TRUE(st.ipopt_succeeded) << k;
        continue;
      }
      EXPECT_EQ(st.index, s.steps[k - 1].index);
      if (k + 1 < s.steps.size()) {
        ++failed;
        EXPECT_FALSE(st.ipopt_succeeded) << k;
        EXPECT_EQ(st.left_zero, 1) << k;  // the wrong branch, x = 0
        EXPECT_EQ(st.by_trend, 0) << k;
        EXPECT_FALSE(st.note.empty()) << k;
        if (by_bound) {
          EXPECT_EQ(st.ipopt_status, "Not_Solved");
          EXPECT_EQ(st.ipopt_iterations, 0);
          EXPECT_NE(st.note.find("outside its bounds"), std::string::npos) << st.note;
        } else {
          EXPECT_NE(st.ipopt_status, "Solve_Succeeded");
        }
      } else {
        // At sigma = 1e-3 y = 0.1 falls with sigma, x = 0.01 does not: the trend picks y = 0,
        // against the distances.
        EXPECT_TRUE(st.ipopt_succeeded);
        EXPECT_EQ(st.right_zero, 1);  // y = 0
        EXPECT_EQ(st.by_trend, 1);
        EXPECT_EQ(st.index, 3);
      }
    }
    EXPECT_GE(failed, 2);
    EXPECT_EQ(s.x[1], 0.0);
    EXPECT_NEAR(s.x[0], 0.01, 1e-9);
    EXPECT_EQ(s.complementarity, 0.0);
    EXPECT_NEAR(s.objective, 1.0002, 1e-9);
    EXPECT_EQ(count_lines(progress.str()), static_cast<int>(s.steps.size()));
    EXPECT_NE(progress.str().find("failed: "), std::string::npos);
    // A polish line names its worst row exactly when its point violates the constraints by more
    // than polish_feasibility_tolerance (lines and steps are in the same order).
    std::istringstream lines(progress.str());
    std::string line;
    int infeasible_polishes = 0;
    for (std::size_t k = 0; k < s.steps.size() && std::getline(lines, line); ++k) {
      if (!s.steps[k].polish) continue;
      const bool infeasible = s.steps[k].constraint_violation > options.polish.feasibility_tolerance;
      infeasible_polishes += infeasible ? 1 : 0;
      EXPECT_EQ(line.find("worst: ") != std::string::npos, infeasible && !s.steps[k].worst_violation.empty()) << line;
    }
    if (!by_bound) {
      EXPECT_GE(infeasible_polishes, 1);  // Ipopt's end point of an infeasible branch
    }
    int total = 0;
    for (const MpccHomotopyStep& st : s.steps) total += st.ipopt_iterations;
    EXPECT_EQ(total, s.ipopt_iterations);

    // A homotopy cut short at sigma = 0.1 (y = 1, the wrong branch still): its final polish
    // fails, and the result is the last step's, not converged, reported as such.
    MpccSolverOptions short_run;
    short_run.homotopy.max_steps = 2;
    const MpccSolution c = solve_mpcc(problem, short_run);
    print_steps(title + ", 2 steps", c);
    EXPECT_FALSE(c.converged);
    EXPECT_FALSE(c.polished);
    ASSERT_EQ(c.steps.size(), 3u);
    EXPECT_TRUE(c.steps[2].polish);
    EXPECT_FALSE(c.steps[2].ipopt_succeeded);
    EXPECT_NE(c.message.find("not converged"), std::string::npos) << c.message;
    EXPECT_NEAR(c.complementarity, c.steps[1].complementarity, 1e-15);
    EXPECT_NEAR(c.x[1], 1.0, 1e-6);  // the relaxed solution at sigma = 0.1: y = 1
  }
}

// Sides that the bounds keep nonnegative need no row. Variables: l1..l5, q (free), a1, a2 in
// [0, 1]. Pairs: l1 _|_ a1 + a2, l2 _|_ 2 - a1 - a2, l3 _|_ 1 - a1, l4 _|_ a1 + a2 (repeated),
// l5 _|_ 1 + 3 a1 - a2 (least value 1 + 0 - 1 = 0), q _|_ a1 - 0.5. Rows are needed only for q
// (no bound) and a1 - 0.5 (least value -0.5): 2 sign rows (before pruning: 6 distinct sides).
class BoundedSums : public Mpcc {
 public:
  int variable_count() const override { return 8; }
  int constraint_count() const override { return 1; }
  void bounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu, Eigen::Ref<Eigen::VectorXd> gl,
              Eigen::Ref<Eigen::VectorXd> gu) const override {
    xl << 0, 0, 0, 0, 0, -inf, 0, 0;
    xu << inf, inf, inf, inf, inf, inf, 1, 1;
    gl << -inf;
    gu << 10.0;
  }
  void initial_point(Eigen::Ref<Eigen::VectorXd> x) const override { x.setConstant(0.5); }
  static Eigen::VectorXd target() {
    Eigen::VectorXd t(8);
    t << 1.0, 0.5, 0.3, 0.2, 0.4, 1.0, 0.7, 0.2;
    return t;
  }
  double objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    return (x - target()).squaredNorm();
  }
  void objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> d) const override {
    d = 2.0 * (x - target());
  }
  void constraints(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const override {
    g << x.head(5).sum();
  }
  const std::vector<SparseEntry>& jacobian_structure() const override { return jac_; }
  void jacobian_values(const Eigen::Ref<const Eigen::VectorXd>&, Eigen::Ref<Eigen::VectorXd> v) const override {
    v.setOnes();
  }
  const std::vector<SparseEntry>& hessian_structure() const override { return hess_; }
  void hessian_values(const Eigen::Ref<const Eigen::VectorXd>&, double s, const Eigen::Ref<const Eigen::VectorXd>&,
                      Eigen::Ref<Eigen::VectorXd> v) const override {
    v.setConstant(2.0 * s);
  }
  const std::vector<ComplementarityPair>& complementarity_pairs() const override { return pairs_; }

 private:
  std::vector<SparseEntry> jac_{{0, 0}, {0, 1}, {0, 2}, {0, 3}, {0, 4}};
  std::vector<SparseEntry> hess_{{0, 0}, {1, 1}, {2, 2}, {3, 3}, {4, 4}, {5, 5}, {6, 6}, {7, 7}};
  std::vector<ComplementarityPair> pairs_{
      {variable(0), AffineExpression{{{6, 1.0}, {7, 1.0}}, 0.0}, "l1 _|_ a1 + a2"},
      {variable(1), AffineExpression{{{6, -1.0}, {7, -1.0}}, 2.0}, "l2 _|_ 2 - a1 - a2"},
      {variable(2), AffineExpression{{{6, -1.0}}, 1.0}, "l3 _|_ 1 - a1"},
      {variable(3), AffineExpression{{{7, 1.0}, {6, 1.0}}, 0.0}, "l4 _|_ a2 + a1"},
      {variable(4), AffineExpression{{{6, 3.0}, {7, -1.0}}, 1.0}, "l5 _|_ 1 + 3 a1 - a2"},
      {variable(5), AffineExpression{{{6, 1.0}}, -0.5}, "q _|_ a1 - 0.5"}};
};

TEST(MpccSolver, SidesKeptNonnegativeByTheBoundsGetNoRow) {
  BoundedSums problem;
  for (const bool polish : {false, true}) {
    std::ostringstream progress;
    MpccSolverOptions options;
    options.polish.enabled = polish;
    options.progress = &progress;
    const MpccSolution s = solve_mpcc(problem, options);
    print_steps(polish ? "BoundedSums, polished" : "BoundedSums, homotopy only", s);
    std::cout << progress.str() << "  x = " << s.x.transpose() << "\n";
    EXPECT_EQ(s.sign_rows, 2);
    EXPECT_EQ(s.relaxed_rows, 1 + 2 + 6);  // m + sign rows + relaxation rows
    ASSERT_TRUE(s.converged) << s.message;
    EXPECT_LE(s.constraint_violation, 1e-9);
    EXPECT_EQ(s.polished, polish);
    // The pruned sides still hold: the bounds hold exactly (bound_relax_factor = 0).
    EXPECT_GE(s.x.tail(2).minCoeff(), 0.0);
    EXPECT_LE(s.x.tail(2).maxCoeff(), 1.0);
    if (polish) {
      // Every zero side is a fixed variable (the sums by their bounds): exactly complementary.
      EXPECT_EQ(s.complementarity, 0.0);
      EXPECT_NE(progress.str().find("rows 0 ="), std::string::npos) << progress.str();
    }
  }
  MpccSolverOptions penalty;
  penalty.homotopy.relaxation = MpccSolverOptions::Relaxation::Penalty;
  const MpccSolution p = solve_mpcc(problem, penalty);
  EXPECT_EQ(p.sign_rows, 2);
  EXPECT_EQ(p.relaxed_rows, 1 + 2);
}

// A wrong guess of a biactive pair's branch (solve.hpp, "POLISHING"), on the mechanism of an
// impact's frozen phase in FESD time-freezing. Variables y (the gap), ln, lp >= 0 (its
// multipliers), a in [0, 1] (the step function); y = lp - ln, y = -2e-5 (a gap that drifted negative), pairs ln _|_ a and
// lp _|_ 1 - a; min (a - 0.5)^2 + ln^2 + lp^2. Feasible only with ln >= 2e-5 > 0, so a = 0, lp =
// 0: the unique solution, f = 0.25 + 4e-10. The Scholtes solution at sigma has ln = 2e-5 and
// a = sigma / 2e-5 (the objective pulls a up): at sigma = 5e-10 (sigma_0, one homotopy step, so
// no trend from a previous step) a = 2.5e-5, both sides below sqrt(1e-9) = 3.2e-5: biactive,
// and the rule zeroes the smaller, ln: the branch y = lp >= 0, infeasible (the other branch, a = 0,
// is the solution: flipping biactive pairs was measured and removed,
// docs/decisions/mpcc-polish-fallback.md).
// With `decoy`, a second biactive pair m _|_ b, b >= 2.4e-5 by its bound, min (m - 0.5)^2 + b^2:
// relaxed m = sigma / 2.4e-5 = 2.08e-5 < b, the rule zeroes m, right (the solution has m = 0,
// b = 2.4e-5).
class BiactiveWrongGuess : public Mpcc {
 public:
  static constexpr double gap = -2e-5;
  explicit BiactiveWrongGuess(bool decoy) : decoy_(decoy) {
    if (decoy_) pairs_.push_back({variable(4), variable(5), "m _|_ b"});
  }
  int variable_count() const override { return decoy_ ? 6 : 4; }  // y, ln, lp, a [, m, b]
  int constraint_count() const override { return 2; }
  void bounds(Eigen::Ref<Eigen::VectorXd> xl, Eigen::Ref<Eigen::VectorXd> xu, Eigen::Ref<Eigen::VectorXd> gl,
              Eigen::Ref<Eigen::VectorXd> gu) const override {
    xl.head(4) << -inf, 0.0, 0.0, 0.0;
    xu.head(4) << inf, inf, inf, 1.0;
    if (decoy_) {
      xl.tail(2) << 0.0, 2.4e-5;
      xu.tail(2) << inf, inf;
    }
    gl << 0.0, gap;
    gu << 0.0, gap;
  }
  void initial_point(Eigen::Ref<Eigen::VectorXd> x) const override {
    x.setConstant(0.5);
    x[0] = 0.0;
  }
  double objective(const Eigen::Ref<const Eigen::VectorXd>& x) const override {
    double f = (x[3] - 0.5) * (x[3] - 0.5) + x[1] * x[1] + x[2] * x[2];
    if (decoy_) f += (x[4] - 0.5) * (x[4] - 0.5) + x[5] * x[5];
    return f;
  }
  void objective_gradient(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> d) const override {
    d.head(4) << 0.0, 2 * x[1], 2 * x[2], 2 * (x[3] - 0.5);
    if (decoy_) d.tail(2) << 2 * (x[4] - 0.5), 2 * x[5];
  }
  void constraints(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> g) const override {
    g << x[0] - x[2] + x[1], x[0];
  }
  const std::vector<SparseEntry>& jacobian_structure() const override { return jac_; }
  void jacobian_values(const Eigen::Ref<const Eigen::VectorXd>&, Eigen::Ref<Eigen::VectorXd> v) const override {
    v << 1.0, -1.0, 1.0, 1.0;
  }
  const std::vector<SparseEntry>& hessian_structure() const override { return decoy_ ? hess_decoy_ : hess_; }
  void hessian_values(const Eigen::Ref<const Eigen::VectorXd>&, double s, const Eigen::Ref<const Eigen::VectorXd>&,
                      Eigen::Ref<Eigen::VectorXd> v) const override {
    v.setConstant(2.0 * s);
  }
  const std::vector<ComplementarityPair>& complementarity_pairs() const override { return pairs_; }
  std::string variable_name(int i) const override {
    static const char* names[] = {"y", "ln", "lp", "a", "m", "b"};
    return names[i];
  }

 private:
  bool decoy_;
  std::vector<SparseEntry> jac_{{0, 0}, {0, 2}, {0, 1}, {1, 0}};
  std::vector<SparseEntry> hess_{{1, 1}, {2, 2}, {3, 3}};
  std::vector<SparseEntry> hess_decoy_{{1, 1}, {2, 2}, {3, 3}, {4, 4}, {5, 5}};
  std::vector<ComplementarityPair> pairs_{{variable(1), variable(3), "ln _|_ a"},
                                          {variable(2), AffineExpression{{{3, -1.0}}, 1.0}, "lp _|_ 1 - a"}};
};

// The polish's one attempt fails; the relaxed step's point remains (converged by its residual
// 5e-10 <= 1e-9, but not exactly complementary).
TEST(MpccSolver, FailedPolishOfAWronglyGuessedBiactivePairKeepsTheStep) {
  for (const bool decoy : {false, true}) {
    BiactiveWrongGuess problem(decoy);
    const std::string title = decoy ? "BiactiveWrongGuess (with decoy)" : "BiactiveWrongGuess";
    MpccSolverOptions single;
    single.homotopy.sigma_0 = 5e-10;  // one step, <= complementarity_tolerance: no trend
    const MpccSolution u = solve_mpcc(problem, single);
    print_steps(title + ", no fallback", u);
    EXPECT_FALSE(u.polished);
    ASSERT_EQ(u.steps.size(), 2u);
    EXPECT_FALSE(u.steps[1].ipopt_succeeded);
    EXPECT_GT(u.complementarity, 1e-10);
    EXPECT_GT(u.x[3], 1e-5);
  }
}

// A branch whose zero side needs an equality row (two variables, no bound makes it zero):
// NonlinearMpcc's pairs are x0 _|_ x1 + 2 x2 - 1 and x1 - x3 + 0.5 _|_ 3 - x2 + 0.5 x0 + 2 x1.
TEST(MpccSolver, PolishWithAffineZeroSides) {
  NonlinearMpcc problem;
  std::ostringstream progress;
  MpccSolverOptions options;
  options.progress = &progress;
  const MpccSolution s = solve_mpcc(problem, options);
  print_steps("NonlinearMpcc", s);
  std::cout << progress.str() << "  x = " << s.x.transpose() << "\n";
  MpccSolverOptions off;
  off.polish.enabled = false;
  const MpccSolution h = solve_mpcc(problem, off);
  print_steps("NonlinearMpcc, homotopy only", h);
  std::cout << "  x = " << h.x.transpose() << "\n";
  ASSERT_TRUE(h.converged) << h.message;
  ASSERT_TRUE(s.converged) << s.message;
  EXPECT_TRUE(s.polished);
  // The homotopy's point: x0 ~ 0 (its side by its bound: fixed) and 3 - x2 + 0.5 x0 + 2 x1 ~ 0
  // (three variables: an equality row).
  EXPECT_EQ(s.x[0], 0.0);
  EXPECT_GT(h.x[0], 0.0);
  EXPECT_NE(progress.str().find("(fixed 1, rows 1 ="), std::string::npos) << progress.str();
  EXPECT_LE(s.complementarity, 1e-12);
  EXPECT_LE(s.constraint_violation, 1e-9);
  EXPECT_LE((s.x - h.x).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_NEAR(s.objective, h.objective, 1e-8);
  EXPECT_EQ(s.constraint_multipliers.size(), 2);
}

}  // namespace
}  // namespace saltus::timefreezing
