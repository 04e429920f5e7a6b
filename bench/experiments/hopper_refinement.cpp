// The hopper over three holes refined from a footstep schedule (docs/refinement.md, "Hopper").
//
//   hopper_refinement [stance [h [max_iter [height]]]]     (defaults 0.3 0.025 3000 0.1)
//
// Discovery by the time-freezing homotopy finds no contact schedule on this OCP (the relaxed
// hopper floats down to sigma = 0.01: bench/experiments/hopper_discovery), so the schedule here is a user's
// guess, the footsteps the holes leave: four stances (the foot sticking) at x = 0, 1, 2, 3 of
// `stance` seconds each, three flights in between of (T - 4 stance) / 3. The motion guessed: in a
// stance the hip above the foot at height 0.4, at rest; in a flight the hip from one foothold to the
// next on an arc `height` high (the leg straight); zero torques. Neither the contact forces nor
// the push-off are guessed. The OCP is scenes/hopper_holes.hpp as it is (T = 2.5 s, |u| <= 60, the
// 11 path rows at the full holes, the start at rest, the target q(T) = (3, 0.4, 0, 0)). Prints the
// refinement's progress, its result and its checks; writes the result's JSON to
// hopper_refinement.json. About 12 minutes on one thread.
#include "scenes/all_scenes.hpp"
#include "scenes/hopper_holes.hpp"

#include <saltus/timefreezing/refinement/refinement.hxx>
#include <saltus/timefreezing/refinement/refinement_io.hpp>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <numbers>

namespace {

using saltus::scenes::Hopper;
using Ocp = saltus::scenes::HopperOverThreeHoles;

saltus::timefreezing::ScheduleGuess<Hopper> footstep_guess(const Hopper& hopper, double stance, double height) {
  using namespace saltus;
  using namespace saltus::timefreezing;
  const double flight = (Ocp::horizon - 4 * stance) / 3.0;
  ScheduleGuess<Hopper> g;
  Mode<1> stick, open;
  stick[0] = ContactState::stick();
  for (int k = 0; k < 4; ++k) {
    g.schedule.phases.push_back(stick);
    if (k < 3) g.schedule.phases.push_back(open);
  }
  for (std::size_t k = 0; k + 1 < g.schedule.phases.size(); ++k)
    g.schedule.events.push_back(guards_between(hopper, g.schedule.phases[k], g.schedule.phases[k + 1]));
  g.schedule = validated(hopper, g.schedule);
  for (int k = 0; k < 3; ++k) {
    g.event_times.push_back((k + 1) * stance + k * flight);
    g.event_times.push_back((k + 1) * (stance + flight));
  }
  const std::vector<double> events = g.event_times;
  g.state = [events, flight, height](int p, double t) {
    VecT<double, 8> x = VecT<double, 8>::Zero();
    const int foothold = p / 2;
    x[0] = foothold;
    x[1] = 0.4;
    if (p % 2 == 0) return x;
    const double s = (t - events[static_cast<std::size_t>(p - 1)]) / flight, w = std::numbers::pi;
    x[0] += s;
    x[1] += height * std::sin(w * s) * std::sin(w * s);
    x[4] = 1.0 / flight;
    x[5] = height * 2.0 * std::sin(w * s) * std::cos(w * s) * w / flight;
    return x;
  };
  g.input = [](double) { return VecT<double, 2>::Zero(); };
  return g;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace saltus;
  using namespace saltus::timefreezing;
  std::cout << std::unitbuf;
  const double stance = argc > 1 ? std::atof(argv[1]) : 0.3, h = argc > 2 ? std::atof(argv[2]) : 0.025;
  const int max_iter = argc > 3 ? std::atoi(argv[3]) : 3000;
  const double height = argc > 4 ? std::atof(argv[4]) : 0.1;
  const Hopper hopper{};
  const ScheduleGuess<Hopper> guess = footstep_guess(hopper, stance, height);
  std::cout << "schedule: " << describe(hopper, guess.schedule) << "\n";
  OcpHorizon<Hopper> horizon;
  horizon.x0 << Ocp::q0(), Ocp::v0();
  horizon.final_time = Ocp::horizon;
  horizon.control_lower = Eigen::VectorXd::Constant(2, -Ocp::torque_limit);
  horizon.control_upper = Eigen::VectorXd::Constant(2, Ocp::torque_limit);
  RefinementOptions options;
  options.progress = &std::cout;
  options.grid.max_element_duration = h;
  options.ipopt.max_iter = max_iter;
  options.edits.max_edits = 0;
  const RefinementResult<Hopper> r = refine_schedule(hopper, Ocp{}, horizon, guess, options);
  std::cout << r.stage << " (" << r.message << ")\n  objective " << r.objective << ", mode validity "
            << r.mode_validity_violation << ", path rows " << r.path_violation << ", target " << r.terminal_violation
            << ", per-phase re-simulation " << r.phase_resim_max_error << ", open loop " << r.open_loop.max_error << " "
            << r.open_loop.note << ", " << r.seconds << " s\n  events:";
  for (double t : r.event_times) std::cout << " " << t;
  std::cout << "\n";
  for (const PhaseResimulation& p : r.phase_resimulation)
    std::cout << "  phase " << p.phase << ": " << p.max_error << " (x+ " << p.x_plus_error << ") " << p.note << "\n";
  std::ofstream("hopper_refinement.json") << to_json(hopper, r).dump(1) << "\n";
  return r.stage == "refined" ? 0 : 1;
}
