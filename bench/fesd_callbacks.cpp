// fesd_callbacks: CPU time of one call of each NLP callback Ipopt makes per iteration (constraints,
// constraint Jacobian, Lagrangian Hessian) of the two flagship FESD MPCCs on their own grids: the
// plank-box's short landing (the coarse-grid test's problem) and the hopper over three holes.
// The Hessian is the largest share of a plank-box iteration (perf: about 60 % of the coarse-grid
// test's time in the second-order AD); this bench measures what a change to it buys (the contact
// kinematics chained in by ad::compose were measured with it: docs/decisions/fesd-composed-kinematics.md).
//
// Each problem is evaluated at a fixed point inside its bounds (evaluation_point below, seed 7)
// and with fixed multipliers (Eigen's Random after std::srand(11)), so every version of the code
// times the same arithmetic. Before timing, the bench prints a checksum
// of each callback's values: a change that should not change the numbers must keep them (to
// rounding).
//
//   OPENBLAS_NUM_THREADS=1 build/bench/fesd_callbacks [--benchmark_filter=...]
#include "scenes/hopper_holes.hpp"
#include "scenes/plank_box_landing.hpp"

#include <saltus/timefreezing/discretisation/fesd.hpp>

#include <benchmark/benchmark.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <random>

namespace {

using namespace saltus;

// Where the callbacks are timed: inside the variable bounds and away from the initial point (a
// point an iteration could visit, not the start's special values). With w_i uniform in [0, 1) from std::mt19937(seed): a variable
// bounded on both sides sits at the fraction 0.1 + 0.8 w_i of its range, one bounded on one side
// 0.1 + 0.2 w_i inside that bound from the initial point (or from the bound, if the initial point
// is not that far inside), a free one at the initial point plus 0.4 w_i - 0.2.
Eigen::VectorXd evaluation_point(const timefreezing::Mpcc& problem, unsigned seed) {
  const int n = problem.variable_count(), m = problem.constraint_count();
  Eigen::VectorXd x(n), lower(n), upper(n), g_lower(m), g_upper(m);
  problem.initial_point(x);
  problem.bounds(lower, upper, g_lower, g_upper);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    const double w = uniform(rng);
    const bool below = std::isfinite(lower[i]), above = std::isfinite(upper[i]);
    if (below && above) x[i] = lower[i] + (0.1 + 0.8 * w) * (upper[i] - lower[i]);
    else if (below) x[i] = std::max(x[i], lower[i]) + 0.1 + 0.2 * w;
    else if (above) x[i] = std::min(x[i], upper[i]) - 0.1 - 0.2 * w;
    else x[i] += 0.4 * w - 0.2;
  }
  return x;
}

struct Evaluation {
  std::unique_ptr<timefreezing::Mpcc> problem;
  Eigen::VectorXd x, multipliers, g, jacobian, hessian;
};

template <class Scene, class Ocp>
Evaluation make(const timefreezing::FesdOptions& grid) {
  Evaluation e;
  e.problem = std::make_unique<timefreezing::FesdMpcc<Scene, Ocp>>(Ocp::system(), Ocp{}, Ocp::q0(), Ocp::v0(), grid);
  e.x = evaluation_point(*e.problem, 7);
  std::srand(11);
  e.multipliers = Eigen::VectorXd::Random(e.problem->constraint_count());
  e.g.resize(e.problem->constraint_count());
  e.jacobian.resize(static_cast<Eigen::Index>(e.problem->jacobian_structure().size()));
  e.hessian.resize(static_cast<Eigen::Index>(e.problem->hessian_structure().size()));
  return e;
}

// One problem per scene, built on first use.
template <class Scene, class Ocp>
Evaluation& cached() {
  static Evaluation e = make<Scene, Ocp>(Ocp::grid());
  return e;
}
Evaluation& (*const plank_box)() = &cached<scenes::PlankBox, scenes::PlankBoxShortLanding>;
Evaluation& (*const hopper)() = &cached<scenes::Hopper, scenes::HopperOverThreeHoles>;

void constraints(benchmark::State& state, Evaluation& (*which)()) {
  Evaluation& e = which();
  for (auto _ : state) {
    e.problem->constraints(e.x, e.g);
    benchmark::DoNotOptimize(e.g.data());
  }
}
void jacobian(benchmark::State& state, Evaluation& (*which)()) {
  Evaluation& e = which();
  for (auto _ : state) {
    e.problem->jacobian_values(e.x, e.jacobian);
    benchmark::DoNotOptimize(e.jacobian.data());
  }
}
void hessian(benchmark::State& state, Evaluation& (*which)()) {
  Evaluation& e = which();
  for (auto _ : state) {
    e.problem->hessian_values(e.x, 0.5, e.multipliers, e.hessian);
    benchmark::DoNotOptimize(e.hessian.data());
  }
}

void print_checksums(const char* name, Evaluation& e) {
  e.problem->constraints(e.x, e.g);
  e.problem->jacobian_values(e.x, e.jacobian);
  e.problem->hessian_values(e.x, 0.5, e.multipliers, e.hessian);
  std::printf("%s: n = %d, m = %d, Jacobian nonzeros %lld, Hessian entries %lld; sums of |values|: g %.15e, "
              "Jacobian %.15e, Hessian %.15e\n",
              name, e.problem->variable_count(), e.problem->constraint_count(),
              static_cast<long long>(e.jacobian.size()), static_cast<long long>(e.hessian.size()),
              e.g.cwiseAbs().sum(), e.jacobian.cwiseAbs().sum(), e.hessian.cwiseAbs().sum());
}

}  // namespace

BENCHMARK_CAPTURE(constraints, plank_box_short_landing, plank_box)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(jacobian, plank_box_short_landing, plank_box)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(hessian, plank_box_short_landing, plank_box)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(constraints, hopper_over_three_holes, hopper)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(jacobian, hopper_over_three_holes, hopper)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(hessian, hopper_over_three_holes, hopper)->Unit(benchmark::kMicrosecond);

int main(int argc, char** argv) {
  print_checksums("plank-box short landing", plank_box());
  print_checksums("hopper over three holes", hopper());
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
