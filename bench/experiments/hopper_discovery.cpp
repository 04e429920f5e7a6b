// What does discovery see on the hopper over three holes? (docs/refinement.md, "Discovery".)
//
//   hopper_discovery [K [gap_per_sigma [velocity_per_sigma [velocity_max [agreeing [gap_max [contact_side]]]]]]]
//   (defaults 4 0 0 1e-2 2 1e-3 0: the exact reading, the paper's grid; contact_side > 0:
//   FesdOptions::regularisation.contact_side, rho_c)
//
// The flagship OCP (scenes/hopper_holes.hpp, the paper's initialisation: the start state at every
// node, zero torques) by discover_schedule_by_continuation: the hole continuation
// (HopperOverThreeHoles::hole_continuation), then at most K homotopy steps (sigma = 1, 0.1, ...),
// each step's relaxed solution read with DiscoveryOptions::reading (gap_per_sigma [m],
// velocity_per_sigma [m/s] per unit of sigma, velocity_max [m/s]) and its schedule extracted (the
// extraction's micro_flight_gap at least gap_max, as scenes::hopper_discovery_options has it); stops
// when `agreeing` consecutive steps agree. Prints one line per continuation stage and per step,
// then the discovered schedule, its event times and where the foot stands in each stance of the
// reading, and the path rows and target of the last relaxed solution at the full holes.
#include "scenes/all_scenes.hpp"
#include "scenes/hopper_holes.hpp"
#include "scenes/hopper_holes_refinement.hpp"

#include <saltus/timefreezing/refinement/mode_schedule.hxx>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iostream>

int main(int argc, char** argv) {
  using namespace saltus;
  using namespace saltus::timefreezing;
  using Ocp = scenes::HopperOverThreeHoles;
  std::cout << std::unitbuf;
  DiscoveryOptions options;
  options.max_steps = argc > 1 ? std::atoi(argv[1]) : 4;
  options.reading.gap_per_sigma = argc > 2 ? std::atof(argv[2]) : 0.0;
  options.reading.velocity_per_sigma = argc > 3 ? std::atof(argv[3]) : 0.0;
  if (argc > 4) options.reading.velocity_max = std::atof(argv[4]);
  if (argc > 5) options.agreeing_steps = std::atoi(argv[5]);
  if (argc > 6) options.reading.gap_max = std::atof(argv[6]);
  options.extraction.micro_flight_gap = std::max(options.extraction.micro_flight_gap, options.reading.gap_max);
  options.progress = &std::cout;
  const scenes::Hopper hopper{};
  MpccSolverOptions solver = Ocp::solver();
  FesdOptions grid = Ocp::grid();
  if (argc > 7) grid.regularisation.contact_side = std::atof(argv[7]);
  const DiscoveryResult<scenes::Hopper> d = discover_schedule_by_continuation(
      hopper, Ocp::system(), Ocp::hole_continuation(), Ocp{}, Ocp::q0(), Ocp::v0(), grid, solver, options);
  std::cout << d.message << "; " << d.seconds << " s (continuation " << d.continuation_seconds << " s)\n";
  const Ocp::Feasibility f = Ocp::feasibility(d.relaxed.points);
  std::cout << "last relaxed solution: path " << f.path_violation << " (row " << f.worst_row << "), target "
            << f.target_error << "\n";
  {  // the relaxed motion's foot and hip, 2 ms apart, for plots: hopper_discovery_motion.csv
    std::ofstream csv("hopper_discovery_motion.csv");
    csv << "t,foot_x,foot_z,hip_x,hip_z\n";
    const HybridTrajectory<scenes::Hopper>& tr = d.relaxed_reading;
    for (std::size_t k = 0; k < tr.segments.size(); ++k)
      for (double t = tr.segments[k].t_begin; t < tr.segments[k].t_end; t += 2e-3) {
        const VecT<double, 8> x = tr.state(static_cast<int>(k), t);
        const Vec<2> foot = hopper.foot<double>(VecT<double, 4>(x.head<4>()));
        csv << t << "," << foot[0] << "," << foot[1] << "," << x[0] << "," << x[1] << "\n";
      }
  }
  if (!d.schedule_found) return 1;
  const ScheduleGuess<scenes::Hopper>& g = d.discovered.guess;
  std::cout << "schedule: " << describe(hopper, g.schedule) << "\nevent times:";
  for (double t : g.event_times) std::cout << " " << t;
  std::cout << "\n";
  for (std::size_t k = 0; k < g.schedule.phases.size(); ++k) {
    const double t0 = k == 0 ? 0.0 : g.event_times[k - 1], t1 = k < g.event_times.size() ? g.event_times[k] : Ocp::horizon;
    const VecT<double, 8> x = g.state(static_cast<int>(k), 0.5 * (t0 + t1));
    const Vec<2> foot = hopper.foot<double>(VecT<double, 4>(x.head<4>()));
    std::cout << "  phase " << k << " [" << t0 << ", " << t1 << "]: foot at (" << foot[0] << ", " << foot[1] << "), hip at ("
              << x[0] << ", " << x[1] << ")\n";
  }
  for (const ExtractionNote& n : d.discovered.notes) std::cout << "  note: " << n.rule << " [" << n.t_begin << ", " << n.t_end << "]\n";
  return d.settled ? 0 : 2;
}
