// Is the plank-box flagship's re-simulation distance the discretisation's error? (bench/experiments/README.md,
// "Plank-box flat landing", the refinement table.)
//
//   plank_box_refinement [--elements M1,M2,...] [--controls FILE] [--reference-prefix P]
//
// The flagship OCP (scenes/plank_box_landing.hpp, its default grid: N = 15 control intervals of
// 2 finite elements, n_s = 2) is solved once; its optimal inputs u_k and speeds of time s_k are then
// held fixed, and the motion they produce is integrated again by FESD time-freezing simulations on
// finer grids, M elements per control interval. Control interval k of the OCP is the time-freezing
// system y' = s_k F(y, u_k) over the numerical length h_k = T / N (time_freezing_system.hpp): the
// same ODE as y' = F(y, u_k) over s_k h_k, so the simulation runs each interval as its own
// simulate_time_freezing over s_k h_k with the constant input u_k, from the previous interval's end.
// Nothing of the OCP's solution but (q0, v0), u_k and s_k enters. Each simulation's points are read
// as a reference (recover_reference) and re-simulated by the event-driven simulator under the same
// inputs, switched at that simulation's own interval ends (polish): the distance is that
// simulation's discretisation error of the controlled motion. M = 2 is the OCP's own grid (its
// element lengths chosen by the simulation, not by the OCP's cost). The OCP's own distance is
// printed beside it.
//
// --controls FILE: read (q0, v0, u_k, s_k) from FILE if it exists (JSON written by an earlier run),
// else solve the OCP (about 90-130 s) and write them there.
// Output: one table row per M on stdout (elements, Ipopt iterations, seconds, the distance, where
// it is largest, the events found), then a JSON object with the same numbers.
#include "scenes/plank_box_landing.hpp"

#include <saltus/hybrid/reference/resimulation.hpp>
#include <saltus/timefreezing/header_only.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace saltus;
using namespace saltus::timefreezing;
using Ocp = scenes::PlankBoxFlatLanding;
using Scene = scenes::PlankBox;

/// The input law of one control interval: the OCP's u_k, constant.
using ConstantInput = scenes::PlankBoxConstantInput;  // compiled in the scene library

/// A fixed-size vector as a JSON array.
template <class V>
std::vector<double> as_vector(const V& x) {
  return std::vector<double>(x.data(), x.data() + x.size());
}

/// The state's components (x, y, theta: the box; phi: the plank; then their rates) by index.
const char* component_name(int i) {
  static constexpr const char* names[] = {"x", "y", "theta", "phi", "v_x", "v_y", "box_rate", "plank_rate"};
  return i >= 0 && i < 8 ? names[i] : "none";
}

struct Controls {
  Vec<4> q0, v0;
  std::vector<Vec<3>> u;   ///< per control interval [N, N, N m]
  std::vector<double> s;   ///< speed of time per control interval
  double ocp_distance = 0.0;
};

nlohmann::json to_json(const Controls& c) {
  nlohmann::json j;
  j["q0"] = as_vector(c.q0);
  j["v0"] = as_vector(c.v0);
  for (const auto& u : c.u) j["u"].push_back(as_vector(u));
  j["s"] = c.s;
  j["ocp_resim_distance"] = c.ocp_distance;
  return j;
}

Controls from_json(const nlohmann::json& j) {
  Controls c;
  for (int i = 0; i < 4; ++i) {
    c.q0[i] = j.at("q0").at(i).get<double>();
    c.v0[i] = j.at("v0").at(i).get<double>();
  }
  for (const auto& u : j.at("u")) c.u.push_back(Vec<3>(u.at(0).get<double>(), u.at(1).get<double>(), u.at(2).get<double>()));
  c.s = j.at("s").get<std::vector<double>>();
  c.ocp_distance = j.at("ocp_resim_distance").get<double>();
  // The numerical interval length comes from the scene's grid: a file of another grid would be
  // integrated with the wrong lengths.
  const int n = Ocp::grid().grid.control_intervals;
  if (static_cast<int>(c.u.size()) != n || static_cast<int>(c.s.size()) != n)
    throw std::runtime_error("the controls file has " + std::to_string(c.u.size()) + " inputs and " +
                             std::to_string(c.s.size()) + " speeds of time; the flagship's grid has " +
                             std::to_string(n) + " control intervals");
  return c;
}

Controls solve_flagship() {
  const FesdOptions grid = Ocp::grid();
  MpccSolverOptions solver = Ocp::solver();
  solver.progress = &std::cerr;
  const Ocp ocp;
  const TimeFreezingOcpResult<Scene> r = solve_time_freezing_ocp(Ocp::system(), ocp, Ocp::q0(), Ocp::v0(), grid, solver);
  const FesdMpcc<Scene, Ocp> problem(Ocp::system(), ocp, Ocp::q0(), Ocp::v0(), grid);  // its variables' layout
  if (!r.converged()) throw std::runtime_error("the plank-box OCP did not converge: " + r.solution.message);
  Controls c;
  c.q0 = Ocp::q0();
  c.v0 = Ocp::v0();
  for (int k = 0; k < grid.grid.control_intervals; ++k) {
    c.u.push_back(r.solution.x.segment<3>(problem.control_index(k)));
    c.s.push_back(r.solution.x[problem.speed_index(k)]);
  }
  c.ocp_distance = polish(Scene{}, r.reference).state_distance;
  return c;
}

struct Row {
  int elements = 0;
  bool converged = false;
  int iterations = 0;
  double seconds = 0.0, distance = 0.0, worst_t = 0.0;
  double x_plus_advance = 0.0;  ///< the largest x_plus_time - t over the impacts [s]
  double distance_away_from_impacts = 0.0;  ///< as distance, over the samples > 2 ms from an impact
  /// The simulation's impacts as recover_trajectory reads them: time [s] and number of guards
  /// (2: both corners in one impact).
  std::vector<std::pair<double, int>> impacts;
  int worst_component = -1;
  std::vector<double> events;
  std::vector<std::string> retries;
  std::string message;
};

/// The reference read from a simulation (samples t, x, u, their segments, the event times), for
/// inspection: --reference-prefix P writes P<M>.json per element count M.
nlohmann::json reference_json(const ImportedReference<Scene>& ref) {
  nlohmann::json j;
  j["t"] = ref.t;
  for (std::size_t k = 0; k < ref.size(); ++k) {
    j["x"].push_back(as_vector(ref.x[k]));
    j["u"].push_back(as_vector(ref.u[k]));
  }
  j["segment"] = ref.segment;
  j["event_times"] = ref.event_times;
  return j;
}

Row simulate(const Controls& c, int elements, const std::string& reference_prefix) {
  const FesdOptions ocp_grid = Ocp::grid();
  const double h = ocp_grid.grid.horizon / ocp_grid.grid.control_intervals;  // numerical length of an interval
  // A simulation's settings (those of test_time_freezing's plank-box landing against the
  // event-driven simulator), not the OCP's: cross-complementarity on every switching function
  // (FesdOptions' default), so that the grid locates the end of the impact and the slip-stick
  // switch too, and the integrated gaps; Scholtes' homotopy from sigma = 1e-3. (With the OCP's
  // settings, velocity switches left to the smoothing from sigma = 1e-2, interval 5 of the 2-element
  // simulation stalled at 3.3e-5 after 60,876 iterations in all.)
  FesdOptions piece;
  piece.grid.stages = ocp_grid.grid.stages;
  piece.switching.integrated_gap = true;
  piece.grid.control_intervals = 1;
  piece.grid.finite_elements = elements;
  MpccSolverOptions solver;
  solver.homotopy.sigma_0 = 1e-3;
  Row row;
  row.elements = elements;
  row.converged = true;
  std::vector<FesdPoint<FesdMpcc<Scene>::ny, FesdMpcc<Scene>::nsw, 3>> points;
  Vec<4> q = c.q0, v = c.v0;
  double tau0 = 0.0, t0 = 0.0;
  for (std::size_t k = 0; k < c.u.size(); ++k) {
    piece.grid.horizon = c.s[k] * h;
    piece.clock.initial_time = t0;
    // The previous interval's end may sit below a contact by the discretisation's drift (gap(q) against
    // the integrated gap: 1e-5 m measured here), as simulate_time_freezing allows between its pieces.
    if (k > 0) piece.bounds.gap_tolerance = std::numeric_limits<double>::infinity();
    // An interval whose homotopy fails (measured: Ipopt's Infeasible_Problem_Detected at the first
    // step, sigma = 1e-3, in one interval of the 2- and of the 4-element simulations) is solved again
    // from a looser first relaxation, sigma_0 = 1e-2, then 1e-1; every attempt's iterations count.
    TimeFreezingSimulation<Scene> sim;
    for (double sigma_0 : {solver.homotopy.sigma_0, 1e-2, 1e-1}) {
      MpccSolverOptions attempt = solver;
      attempt.homotopy.sigma_0 = sigma_0;
      sim = simulate_time_freezing(Ocp::system(), q, v, piece, ConstantInput{c.u[k]}, attempt);
      row.iterations += sim.solution.ipopt_iterations;
      row.seconds += sim.solution.seconds;
      if (sigma_0 != solver.homotopy.sigma_0)
        row.retries.push_back("interval " + std::to_string(k) + " from sigma_0 = " + (sigma_0 < 0.05 ? "1e-2" : "1e-1") +
                              (sim.converged() ? ": converged" : ": not converged"));
      if (sim.converged()) break;
    }
    if (!sim.converged()) {
      row.converged = false;
      if (row.message.empty()) row.message = "interval " + std::to_string(k) + ": " + sim.solution.message;
    }
    for (std::size_t i = (k == 0 ? 0 : 1); i < sim.points.size(); ++i) {
      auto p = sim.points[i];
      p.tau += tau0;
      p.interval = static_cast<int>(k);
      points.push_back(p);
    }
    const auto& end = points.back().y;
    q = end.head<4>();
    v = end.segment<4>(4);
    t0 = end[TimeFreezingSystem<Scene>::clock_index];
    tau0 += piece.grid.horizon;
  }
  // Read as the OCP's reference is (solve_time_freezing_ocp): where a frozen run ends before the
  // impact does, its x+ sample is the state where the impact ends, at that state's time
  // (recover_trajectory's docstring, x_plus_time): measured 2.8e-3 s after the impact at 30-120
  // elements, 1.2e-4 s at 480.
  const HybridTrajectory<Scene> traj = recover_trajectory<Scene>(Ocp::system(), points, piece.grid.stages);
  const ImportedReference<Scene> ref = recover_reference<Scene>(traj, points, piece.grid.stages);
  for (std::size_t e = 0; e < traj.events.size(); ++e)
    if (traj.events[e].impact()) {
      row.x_plus_advance = std::max(row.x_plus_advance, x_plus_time(traj, e) - traj.events[e].t);
      row.impacts.push_back({traj.events[e].t, static_cast<int>(traj.events[e].guards().size())});
    }
  if (!reference_prefix.empty())
    std::ofstream(reference_prefix + std::to_string(elements) + ".json") << reference_json(ref).dump() << "\n";
  const PolishResult<Scene> resim = polish(Scene{}, ref);
  // The distance away from the impacts (samples more than 2 ms from every impact event of the
  // re-simulation, compared with its state at their time), and the samples within 1 ms of an
  // impact on stderr: where polish's largest distance sits at an impact, these say whether the
  // rest of the motion agrees. (state_at is the post-impact state from the simulated impact on,
  // so a pre-impact sample stamped a hair after it reads the jump here: 0.74 for x- at 120 and 240
  // elements, where polish, which pairs the events, finds it within 2e-10 at 120.)
  std::vector<double> impact_times;
  for (const auto& ev : resim.trajectory.events)
    if (ev.impact()) impact_times.push_back(ev.t);
  for (std::size_t j = 0; j < ref.size(); ++j) {
    double nearest = std::numeric_limits<double>::infinity();
    for (double t : impact_times) nearest = std::min(nearest, std::abs(ref.t[j] - t));
    const double d = (ref.x[j] - resim.trajectory.state_at(ref.t[j])).cwiseAbs().maxCoeff();
    if (nearest > 2e-3) row.distance_away_from_impacts = std::max(row.distance_away_from_impacts, d);
    if (nearest <= 1e-3)
      std::fprintf(stderr, "%d elements per interval: sample %zu at t = %.9f (segment %d), %.3e from the re-simulation\n",
                   elements, j, ref.t[j], ref.segment_of(j), d);
  }
  row.distance = resim.state_distance;
  row.worst_t = resim.worst_sample_time;
  row.worst_component = resim.worst_component;
  for (const auto& ev : resim.trajectory.events) row.events.push_back(ev.t);
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> element_counts{2, 4, 8, 16};
  std::string controls_file, reference_prefix;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--elements") == 0 && i + 1 < argc) {
      element_counts.clear();
      std::stringstream list(argv[++i]);
      for (std::string item; std::getline(list, item, ',');) {
        char* end = nullptr;
        const long m = std::strtol(item.c_str(), &end, 10);
        if (*end != '\0' || m < 1 || m > 256) {
          std::fprintf(stderr, "plank_box_refinement: bad element count '%s'\n", item.c_str());
          return 2;
        }
        element_counts.push_back(static_cast<int>(m));
      }
    } else if (std::strcmp(argv[i], "--controls") == 0 && i + 1 < argc) {
      controls_file = argv[++i];
    } else if (std::strcmp(argv[i], "--reference-prefix") == 0 && i + 1 < argc) {
      reference_prefix = argv[++i];
    } else {
      const bool help = std::strcmp(argv[i], "--help") == 0;
      std::fprintf(help ? stdout : stderr,
                   "usage: plank_box_refinement [--elements M1,M2,...] [--controls FILE] [--reference-prefix P]\n"
                   "  the plank-box flagship's optimal inputs integrated again with M elements per control\n"
                   "  interval (default 2,4,8,16) and re-simulated (bench/experiments/README.md); --controls FILE reads\n"
                   "  the inputs from FILE if it exists, else solves the OCP and writes them there;\n"
                   "  --reference-prefix P writes each simulation's reference (samples, segments, events) to\n"
                   "  P<M>.json.\n");
      return help ? 0 : 2;
    }
  }
  Controls c;
  try {
    std::ifstream in(controls_file);
    if (!controls_file.empty() && in) {
      c = from_json(nlohmann::json::parse(in));
      std::fprintf(stderr, "controls read from %s\n", controls_file.c_str());
    } else {
      c = solve_flagship();
      if (!controls_file.empty()) std::ofstream(controls_file) << to_json(c).dump(1) << "\n";
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "plank_box_refinement: %s%s: %s\n", controls_file.empty() ? "" : "controls file ",
                 controls_file.c_str(), e.what());
    return 1;
  }
  const int intervals = static_cast<int>(c.u.size());
  std::printf("the OCP's own re-simulation distance (N = %d, %d elements per interval): %.3g\n", intervals,
              Ocp::grid().grid.finite_elements, c.ocp_distance);
  // Columns: the simulation's elements (M per interval), whether every interval's homotopy
  // converged, Ipopt iterations and the sum of the solves' seconds, the re-simulation's largest
  // state distance, the time and state component where it is largest, the largest clock advance
  // of an impact's x+ (x_plus_time - t, 0 when every frozen run ends with its impact), and the
  // re-simulation's events (the impact, the stop, the lift-off).
  std::printf("%8s %5s %7s %8s %10s %8s %-12s %9s  %s\n", "elements", "conv", "iters", "seconds", "distance", "at t",
              "component", "x+ adv", "events (re-simulation)");
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (int m : element_counts) {
    const Row r = simulate(c, m, reference_prefix);
    std::string events;
    for (double t : r.events) events += (events.empty() ? "" : ", ") + std::to_string(t);
    for (const std::string& retry : r.retries) std::fprintf(stderr, "%d elements per interval: %s\n", m, retry.c_str());
    std::fprintf(stderr, "%d elements per interval: distance more than 2 ms from the impacts %.3e\n", m,
                 r.distance_away_from_impacts);
    for (const auto& [t, guards] : r.impacts)
      std::fprintf(stderr, "%d elements per interval: an impact at t = %.9f with %d guards\n", m, t, guards);
    std::printf("%8d %5s %7d %8.1f %10.3e %8.4f %-12s %9.2e  %s %s\n", m * intervals, r.converged ? "yes" : "no",
                r.iterations, r.seconds, r.distance, r.worst_t, component_name(r.worst_component), r.x_plus_advance,
                events.c_str(), r.message.c_str());
    std::fflush(stdout);
    rows.push_back({{"elements_per_interval", m},
                    {"elements", m * intervals},
                    {"converged", r.converged},
                    {"ipopt_iterations", r.iterations},
                    {"seconds", r.seconds},
                    {"resim_distance", r.distance},
                    {"worst_t", r.worst_t},
                    {"worst_component", component_name(r.worst_component)},
                    {"x_plus_advance", r.x_plus_advance},
                    {"distance_away_from_impacts", r.distance_away_from_impacts},
                    {"impacts", r.impacts},
                    {"events", r.events},
                    {"retries", r.retries},
                    {"failure", r.message}});
  }
  nlohmann::ordered_json out;
  out["ocp_resim_distance"] = c.ocp_distance;
  out["rows"] = rows;
  std::cout << out.dump(1) << "\n";
  return 0;
}
