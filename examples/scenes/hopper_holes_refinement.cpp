// The hopper's mode-schedule refinement, compiled once, and its chain's settings
// (hopper_holes_refinement.hpp).
#include "scenes/hopper_holes_refinement.hpp"

#include <saltus/timefreezing/instantiate.hxx>

#include <cmath>

SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT_SCENE(saltus::scenes::Hopper)
SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT(saltus::scenes::Hopper, saltus::scenes::HopperOverThreeHoles)

namespace saltus::scenes {

timefreezing::DiscoveryOptions hopper_discovery_options(int steps, std::ostream* progress) {
  timefreezing::DiscoveryOptions o;
  o.max_steps = steps;
  o.extraction.micro_flight_gap = 0.015;
  o.reading.gap_per_sigma = 0.15;
  o.reading.gap_max = 0.015;
  o.reading.velocity_per_sigma = 100.0;
  o.reading.velocity_max = 10.0;
  o.progress = progress;
  return o;
}

timefreezing::RefinementOptions hopper_refinement_options(std::ostream* progress) {
  timefreezing::RefinementOptions o;
  o.grid.max_element_duration = 0.05;
  o.grid.stages = 4;
  o.ipopt.max_iter = 3000;
  o.edits.max_edits = 0;
  o.stick_cone_margin = 0.05;
  o.min_phase_duration = 0.02;
  o.contact_stabilisation = 20.0;
  o.flight_clearance = 0.005;
  o.stance_load = 20.0;
  o.touchdown_speed = 0.3;
  o.mesh.local_error_tolerance = 2e-8;
  o.mesh.max_split = 4;
  o.mesh.max_rounds = 10;
  o.mesh.max_iter = 1000;
  o.mesh.warm_start_mu = 0.1;
  o.checks.resimulation_window = 0.02;
  o.progress = progress;
  return o;
}

timefreezing::OcpHorizon<Hopper> hopper_refinement_horizon(double T) {
  using Ocp = HopperOverThreeHoles;
  SALTUS_REQUIRE(std::isfinite(T) && T > 0.0, "hopper_refinement_horizon: T must be finite and > 0, got ", T);
  timefreezing::OcpHorizon<Hopper> h;
  h.x0 << Ocp::q0(), Ocp::v0();
  h.final_time = T;
  h.control_lower = Eigen::VectorXd::Constant(2, -Ocp::torque_limit);
  h.control_upper = Eigen::VectorXd::Constant(2, Ocp::torque_limit);
  return h;
}

timefreezing::ScheduleGuess<Hopper> hopper_guess_from(const timefreezing::DiscoveryResult<Hopper>& discovery,
                                                      HopperFootsteps* footsteps, const Vec<4>& q_end, double T) {
  using Ocp = HopperOverThreeHoles;
  SALTUS_REQUIRE(discovery.schedule_found, "hopper_guess_from: discovery found no schedule (", discovery.message, ")");
  const Hopper hopper{};
  const HopperFootsteps steps = footsteps_of(hopper, discovery.discovered.guess, Ocp::q0(), q_end, T);
  if (footsteps) *footsteps = steps;
  return footstep_guess(hopper, steps, Ocp::q0(), q_end, T);
}

}  // namespace saltus::scenes
