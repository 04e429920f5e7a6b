// jump_gains: analytic jump gains (thesis C.37-C.39, AD of guard, flow and jump map) against
// their numerical twin (central differences through re-simulation), per scene and event kind:
//   fd_rel_error       max |G_analytic - G_twin| / max |G| over G_z (on the admissible ante-event
//                      deviations, numerical_jump_gain.hpp) and G_v
//   dt_rel_error       the same for the first-order event-time shift [dt_dz B, dt_dv] against the
//                      twin's perturbed event times
//   slope              fitted log-log slope of the first-order prediction's remainder
//                      |x_eps - x_k - eps z_k| over eps = 1e-2..1e-6, for a perturbed state at the
//                      start, sampled in the segment after the event (2 means exact first order),
//                      fitted on the points at least 30x above the smallest remainder (the
//                      integration floor: remainder_slope.hpp); "exact" when every remainder is
//                      at round-off (the motion is linear in the perturbation)
//   slope_points       how many of the 5 eps values that fit used
//   remainders         r(eps) for eps = 1e-2, ..., 1e-6 (JSON only)
//   gain_us            wall time of one analytic gain (JumpGainSolver::compute), microseconds
//   numerical_twin_us  wall time of one numerical twin (numerical_jump_gain), microseconds
// Both times are measured in the same run, so their ratio is the meaningful figure.
// Plain main; `--json` prints one JSON object, otherwise a table.
#include "remainder_slope.hpp"
#include "scenes/references.hpp"
#include <saltus/sensitivity/prediction_check.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

namespace {

using namespace saltus;
using Clock = std::chrono::steady_clock;

struct Row {
  std::string scene, kind;
  double fd_rel_error = 0, dt_rel_error = 0, slope = 0, gain_us = 0, twin_us = 0;
  int slope_points = 0;
  bool exact = false;
  std::vector<double> remainders;  ///< r(eps) for eps = 1e-2..1e-6
};

template <class F>
double microseconds_per_call(F&& f, double min_seconds) {
  long n = 0;
  const auto start = Clock::now();
  double elapsed = 0;
  do {
    f();
    ++n;
    elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  } while (elapsed < min_seconds);
  return 1e6 * elapsed / static_cast<double>(n);
}

template <Scene S>
void measure(const references::Reference<S>& ref, const Vec<2 * S::nq>& z0, std::vector<Row>& rows,
             double twin_step = 3e-5, double extension = 0.1) {
  const auto& traj = ref.trajectory;
  JumpGainSolver<S> solver(ref.scene);
  NumericalJumpGainOptions twin;
  twin.simulation = ref.options;
  twin.state_step = twin.input_step = twin_step;
  LinearisationOptions lo;
  lo.variational.relative = lo.variational.absolute = 1e-13;
  lo.spreading.before = lo.spreading.after = extension;
  const LinearisedSystem<S> lin(ref.scene, traj, lo);
  for (int e = 0; e < static_cast<int>(traj.events.size()); ++e) {
    Row row;
    row.scene = ref.name;
    row.kind = references::event_kind(ref.scene, traj.events[e]);
    const JumpGain<S> a = solver.compute(traj.events[e], traj.input);
    const NumericalJumpGain<S> n = numerical_jump_gain(ref.scene, traj, e, twin);
    // On the admissible ante-event deviations (numerical_jump_gain.hpp): G_z B against the twin's.
    const Eigen::MatrixXd GzB = a.G_z * n.basis;
    const double scale = std::max({GzB.cwiseAbs().maxCoeff(), n.G_z_basis.cwiseAbs().maxCoeff(),
                                   a.G_v.cwiseAbs().maxCoeff()});
    row.fd_rel_error =
        std::max((GzB - n.G_z_basis).cwiseAbs().maxCoeff(), (a.G_v - n.G_v).cwiseAbs().maxCoeff()) / scale;
    if (a.info.front().guarded) {
      const Eigen::RowVectorXd dtB = a.dt_dz * n.basis;
      const double dt_scale = std::max({dtB.cwiseAbs().maxCoeff(), a.dt_dv.cwiseAbs().maxCoeff()});
      row.dt_rel_error = std::max((dtB - n.dt_basis).cwiseAbs().maxCoeff(), (a.dt_dv - n.dt_dv).cwiseAbs().maxCoeff()) /
                         dt_scale;
    }
    row.gain_us = microseconds_per_call([&] { solver.compute(traj.events[e], traj.input); }, 0.2);
    row.twin_us = microseconds_per_call([&] { numerical_jump_gain(ref.scene, traj, e, twin); }, 0.5);
    // Remainder sampled in the middle of the segment after the event.
    const double t_next = e + 1 < static_cast<int>(traj.events.size()) ? traj.events[e + 1].t : traj.t_end();
    const double t_sample = traj.events[e].t + 0.5 * (t_next - traj.events[e].t);
    const auto fit = prediction_remainder(lin, ref.options, z0, [](double) { return Vec<S::nu>::Zero().eval(); },
                                               {t_sample});
    const bench::RemainderSlope slope = bench::slope_above_floor(fit.eps, fit.remainder);
    row.remainders = fit.remainder;
    row.slope_points = slope.points;
    row.exact = slope.exact;
    row.slope = fit.structure_matched ? slope.slope : std::nan("");
    rows.push_back(row);
  }
}

}  // namespace

int main(int argc, char** argv) {
  const bool json = argc > 1 && std::strcmp(argv[1], "--json") == 0;
  std::vector<Row> rows;
  try {
    measure(references::example3(), Vec<4>(0.3, -0.5, 0.7, 0.4), rows);
    measure(references::point_mass_with_friction(), references::point_mass_with_friction_perturbation(), rows);
    measure(references::hopper(), references::hopper_perturbation(), rows);
    measure(references::plank_box(), references::plank_box_perturbation(), rows);
    // PD feedback (closed-loop gains); twin steps 3e-6 and 20 ms extensions, as in the tests.
    measure(references::hopper_push_off(), Vec<8>(3000.0 * references::hopper_push_off_perturbation()), rows, 3e-6, 0.02);
  } catch (const std::exception& e) {
    std::cerr << "jump_gains: " << e.what() << "\n";
    return 1;
  }
  std::ostringstream os;
  os << std::setprecision(4);
  if (json) {
    // {"<scene>": {"<event kind>": {...}}}; repeated kinds within a scene get "#2", "#3".
    // Numbers as the table prints them (4 significant digits); a non-finite one is null.
    const auto number = [](double x) -> nlohmann::ordered_json {
      if (!std::isfinite(x)) return nullptr;
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.4g", x);
      return std::strtod(buf, nullptr);
    };
    std::map<std::string, std::map<std::string, int>> seen;
    nlohmann::ordered_json out = nlohmann::ordered_json::object();
    for (const Row& r : rows) {
      const int k = ++seen[r.scene][r.kind];
      const std::string kind = r.kind + (k > 1 ? " #" + std::to_string(k) : "");
      out[r.scene][kind] = {{"fd_rel_error", number(r.fd_rel_error)},
                            {"dt_rel_error", number(r.dt_rel_error)},
                            {"slope", r.exact ? nlohmann::ordered_json("exact") : number(r.slope)},
                            {"slope_points", r.slope_points},
                            {"remainders", [&] {
                               nlohmann::ordered_json a = nlohmann::ordered_json::array();
                               for (const double x : r.remainders) a.push_back(number(x));
                               return a;
                             }()},
                            {"gain_us", number(r.gain_us)},
                            {"numerical_twin_us", number(r.twin_us)}};
    }
    os << out.dump() << "\n";
  } else {
    os << std::left << std::setw(32) << "scene" << std::setw(36) << "event kind" << std::setw(14) << "fd_rel_error"
       << std::setw(14) << "dt_rel_error" << std::setw(8) << "slope" << std::setw(8) << "points" << std::setw(12) << "gain_us" << "numerical_twin_us\n";
    for (const Row& r : rows)
      os << std::left << std::setw(32) << r.scene << std::setw(36) << r.kind << std::setw(14) << r.fd_rel_error
         << std::setw(14) << r.dt_rel_error << std::setw(8) << std::setprecision(3)
         << (r.exact ? std::string("exact") : [&] { std::ostringstream o; o << std::setprecision(3) << r.slope; return o.str(); }())
         << std::setw(8) << r.slope_points << std::setw(12) << r.gain_us
         << r.twin_us << std::setprecision(4) << "\n";
  }
  std::cout << os.str();
  return 0;
}
