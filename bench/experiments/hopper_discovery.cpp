// What does discovery see on the hopper over three holes? (docs/refinement.md, "Discovery".)
//
//   hopper_discovery [K]      (K = 4 by default)
//
// The flagship OCP (scenes/hopper_holes.hpp, the paper's initialisation: the start state at every
// node, zero torques) with its hole continuation (HopperOverThreeHoles::hole_continuation), the
// homotopy stopped after k = 1..K steps, each run from the start: per k the last step's sigma,
// Ipopt's status, complementarity, objective, the path rows and target at the full holes, the
// recovered trajectory's events (time, impact, hip x), and the schedule extract_schedule reads
// from it. One line per k as it finishes; about 15 minutes for K = 4 on a 2-core machine.
#include "scenes/all_scenes.hpp"
#include "scenes/hopper_holes.hpp"

#include <saltus/timefreezing/drivers/optimal_control.hpp>
#include <saltus/timefreezing/refinement/mode_schedule.hxx>
#include <saltus/timefreezing/refinement/schedule_extraction.hxx>

#include <cstdlib>
#include <iostream>

int main(int argc, char** argv) {
  using namespace saltus;
  using namespace saltus::timefreezing;
  using Ocp = scenes::HopperOverThreeHoles;
  std::cout << std::unitbuf;
  const int steps = argc > 1 ? std::atoi(argv[1]) : 4;
  const scenes::Hopper hopper{};
  for (int k = 1; k <= steps; ++k) {
    MpccSolverOptions solver = Ocp::solver();
    solver.homotopy.max_steps = k;
    solver.polish.enabled = false;
    const auto r = solve_time_freezing_ocp_by_continuation(Ocp::system(), Ocp::hole_continuation(), Ocp{}, Ocp::q0(),
                                                           Ocp::v0(), Ocp::grid(), solver);
    const auto& last = r.solution.steps.back();
    const Ocp::Feasibility f = Ocp::feasibility(r.points);
    std::cout << "k " << k << "  sigma " << last.sigma << "  " << last.ipopt_status << "  compl " << r.solution.complementarity
              << "  f " << r.solution.objective << "  path " << f.path_violation << " (row " << f.worst_row << ")  target "
              << f.target_error << "  " << r.solution.seconds << " s\n  recovered events:";
    for (const auto& e : r.trajectory.events) std::cout << " t " << e.t << (e.impact() ? " impact" : "") << " hip x " << e.x_minus[0] << ";";
    std::cout << (r.trajectory.events.empty() ? " none" : "") << "\n";
    try {
      const ExtractedSchedule<scenes::Hopper> extracted = extract_schedule(hopper, r.trajectory);
      std::cout << "  schedule: " << describe(hopper, extracted.guess.schedule) << "  (" << extracted.notes.size()
                << " extraction notes)\n";
    } catch (const Error& e) {
      std::cout << "  schedule: none (" << e.what() << ")\n";
    }
  }
}
