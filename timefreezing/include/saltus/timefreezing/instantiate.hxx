// The definitions of FesdMpcc and of the time-freezing drivers, and the macros that compile them
// for one scene and one OCP or input law, in one .cpp (see instantiate.hpp for the pattern).
#pragma once

#include <saltus/timefreezing/instantiate.hpp>

#include <saltus/timefreezing/discretisation/fesd.hxx>
#include <saltus/timefreezing/drivers/optimal_control.hxx>
#include <saltus/timefreezing/drivers/simulate.hxx>
#include <saltus/timefreezing/recovery/recover_reference.hxx>
#include <saltus/timefreezing/recovery/recover_trajectory.hxx>
#include <saltus/timefreezing/refinement/discovery.hxx>
#include <saltus/timefreezing/refinement/refinement.hxx>

/// recover_trajectory and recover_reference of scene S's FESD points.
#define SALTUS_INSTANTIATE_TIME_FREEZING_SCENE(S) SALTUS_TIME_FREEZING_SCENE_TEMPLATES(, S)
/// FesdMpcc<S, Ocp> and solve_time_freezing_ocp, _from_guess and _by_continuation.
#define SALTUS_INSTANTIATE_TIME_FREEZING_OCP(S, Ocp) \
  template class saltus::timefreezing::FesdMpcc<S, Ocp>; \
  SALTUS_TIME_FREEZING_OCP_DRIVER_TEMPLATES(, S, Ocp)
/// FesdMpcc<S, Law> and simulate_time_freezing<S, Law>.
#define SALTUS_INSTANTIATE_TIME_FREEZING_SIMULATION(S, Law) \
  template class saltus::timefreezing::FesdMpcc<S, Law>;    \
  SALTUS_TIME_FREEZING_SIMULATION_DRIVER_TEMPLATES(, S, Law)
/// simulate_time_freezing<S, Law> alone (its FesdMpcc instantiated as an OCP).
#define SALTUS_INSTANTIATE_TIME_FREEZING_SIMULATION_DRIVER(S, Law) \
  SALTUS_TIME_FREEZING_SIMULATION_DRIVER_TEMPLATES(, S, Law)
/// resimulate_phases<S> and resimulate_open_loop<S> (refinement.hpp).
#define SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT_SCENE(S) SALTUS_SCHEDULE_REFINEMENT_SCENE_TEMPLATES(, S)
/// ScheduleRefinementNlp<S, Ocp> and refine_schedule<S, Ocp> (refinement.hpp).
#define SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT(S, Ocp)              \
  template class saltus::timefreezing::ScheduleRefinementNlp<S, Ocp>; \
  SALTUS_SCHEDULE_REFINEMENT_OCP_TEMPLATES(, S, Ocp)
