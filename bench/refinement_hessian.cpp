// refinement_hessian: what the refinement NLP's time-invariant stage Hessian buys
// (ScheduleRefinementNlp::stage_hessian, refinement_nlp.hpp). The Lagrangian Hessian is most of an
// Ipopt iteration of the hopper's refinement (measured with print_timing_statistics: 62-65 % of
// every solve of its chain). When the stages depend on time only through the element length h, the
// Hessian is taken over (x, u) alone (10 AD directions for the hopper) and the time rows and
// columns are written from the first-order part; otherwise over all of w = (x, u, t_p, t_{p+1})
// (12). The same OCP is built twice: as it is (the reduced path) and behind an input law
// u(t, d) = d that changes no value but makes the stages formally time-dependent (the full path).
// Both NLPs are evaluated at the same point with the same multipliers: the bench prints the largest
// difference of their Hessian values (rounding only) and the time per call of each, with the ratio,
// in one run.
//
//   OPENBLAS_NUM_THREADS=1 build/bench/refinement_hessian [calls]
//
// The problem: the hopper over three holes (scenes/hopper_holes.hpp) on the holes' footstep schedule
// (stances of 0.3, 0.45, 0.45 and 0.3 s at x = 0, 1, 2, 3, three flights of 1/3 s; scenes::footstep_guess),
// 0.05 s elements, n_s = 3, at the guess, the multipliers uniform in [-1, 1] (std::mt19937(11)).
#include "scenes/hopper_footsteps.hpp"
#include "scenes/hopper_holes.hpp"
#include "scenes/hopper_holes_refinement.hpp"

#include <saltus/timefreezing/refinement/refinement.hxx>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

namespace {

using namespace saltus;
using Ocp = scenes::HopperOverThreeHoles;

/// The hopper's OCP with an input law that returns its decision: the same NLP, evaluated on the
/// stages' full (time-dependent) path.
struct TimedInputHoles : Ocp {
  template <class T>
  VecT<T, 2> input(const T&, const VecT<T, 2>& decision) const {
    return decision;
  }
};

/// Seconds per call of f, the median of `repeats` batches of `calls` calls.
template <class F>
double seconds_per_call(F&& f, int calls, int repeats = 5) {
  std::vector<double> batches;
  for (int r = 0; r < repeats; ++r) {
    const auto start = std::chrono::steady_clock::now();
    for (int k = 0; k < calls; ++k) f();
    batches.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / calls);
  }
  std::nth_element(batches.begin(), batches.begin() + repeats / 2, batches.end());
  return batches[static_cast<std::size_t>(repeats / 2)];
}

}  // namespace

int main(int argc, char** argv) {
  using namespace saltus::timefreezing;
  const int calls = argc > 1 ? std::max(1, std::atoi(argv[1])) : 5;
  const scenes::Hopper hopper{};
  const double flight = (Ocp::horizon - 2 * 0.3 - 2 * 0.45) / 3.0;
  const scenes::HopperFootsteps steps{{0.0, 1.0, 2.0, 3.0},
                                      {0.3, 0.3 + flight, 0.75 + flight, 0.75 + 2 * flight, 1.2 + 2 * flight, 2.2}};
  const ScheduleGuess<scenes::Hopper> guess = scenes::footstep_guess(hopper, steps, Ocp::q0(), Ocp::q_target(), Ocp::horizon);
  RefinementOptions options;
  options.grid.max_element_duration = 0.05;
  options.grid.stages = 3;
  const OcpHorizon<scenes::Hopper> horizon = scenes::hopper_refinement_horizon();
  const ScheduleRefinementNlp<scenes::Hopper, Ocp> reduced(hopper, Ocp{}, horizon, guess, options);
  const ScheduleRefinementNlp<scenes::Hopper, TimedInputHoles> full(hopper, TimedInputHoles{}, horizon, guess, options);
  static_assert(ScheduleRefinementNlp<scenes::Hopper, Ocp>::stages_time_invariant);
  static_assert(!ScheduleRefinementNlp<scenes::Hopper, TimedInputHoles>::stages_time_invariant);
  Eigen::VectorXd x(reduced.variable_count());
  reduced.initial_point(x);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::VectorXd multipliers(reduced.constraint_count());
  for (Eigen::Index j = 0; j < multipliers.size(); ++j) multipliers[j] = uniform(rng);
  const Eigen::Index nnz = static_cast<Eigen::Index>(reduced.hessian_structure().size());
  Eigen::VectorXd h_reduced(nnz), h_full(nnz);
  reduced.hessian_values(x, 1.0, multipliers, h_reduced);
  full.hessian_values(x, 1.0, multipliers, h_full);
  const double scale = std::max(1.0, h_full.cwiseAbs().maxCoeff());
  std::printf("hopper refinement NLP: %d elements, %d variables, %d constraints, %ld Hessian entries\n",
              reduced.element_count(), reduced.variable_count(), reduced.constraint_count(), static_cast<long>(nnz));
  std::printf("largest |H_reduced - H_full| = %.3g (relative to max |H| = %.3g: %.3g)\n",
              (h_reduced - h_full).cwiseAbs().maxCoeff(), scale, (h_reduced - h_full).cwiseAbs().maxCoeff() / scale);
  const double t_reduced = seconds_per_call([&] { reduced.hessian_values(x, 1.0, multipliers, h_reduced); }, calls);
  const double t_full = seconds_per_call([&] { full.hessian_values(x, 1.0, multipliers, h_full); }, calls);
  std::printf("Lagrangian Hessian per call: over (x, u) %.4f s, over (x, u, t_p, t_p+1) %.4f s, ratio %.2f\n", t_reduced,
              t_full, t_full / t_reduced);
  return 0;
}
