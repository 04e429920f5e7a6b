// Compile a scene's time-freezing machinery once per scene and per OCP or input law, as the hybrid
// core does (saltus/hybrid/instantiate.hpp): FesdMpcc and the drivers are declared in their .hpp
// and defined in the .hxx beside them. A program that includes only the .hpp files does not compile
// them; it links them from the one translation unit that instantiates them:
//
//   // my_ocp.hpp: the scene (with SALTUS_DECLARE_SCENE), the OCP, then
//   #include <saltus/timefreezing/instantiate.hpp>
//   struct MyOcp { ... };
//   SALTUS_DECLARE_TIME_FREEZING_SCENE(MyScene)       // the recovery of MyScene's solutions
//   SALTUS_DECLARE_TIME_FREEZING_OCP(MyScene, MyOcp)  // FesdMpcc<MyScene, MyOcp> and the OCP drivers
//
//   // my_ocp.cpp: compiled once, linked with every program that solves MyOcp
//   #include "my_ocp.hpp"
//   #include <saltus/timefreezing/instantiate.hxx>
//   SALTUS_INSTANTIATE_TIME_FREEZING_SCENE(MyScene)
//   SALTUS_INSTANTIATE_TIME_FREEZING_OCP(MyScene, MyOcp)
//
// A simulation under an input law (simulate_time_freezing<S, InputLaw>; NoObjective: u = 0) has
// its own pair, SALTUS_DECLARE_TIME_FREEZING_SIMULATION / SALTUS_INSTANTIATE_TIME_FREEZING_SIMULATION.
// Both pairs compile FesdMpcc<S, X>: a type X used both as an OCP and as an input law takes the OCP
// pair and SALTUS_..._SIMULATION_DRIVER (the driver alone). The types must be named with their
// namespaces (or from the global namespace), at namespace scope. Without any of this, including
// <saltus/timefreezing/header_only.hpp> compiles everything in the including translation unit.
//
// The mode-schedule refinement (refinement/refinement.hpp) has its pairs too:
// SALTUS_DECLARE/INSTANTIATE_SCHEDULE_REFINEMENT_SCENE(S) (the re-simulations of refined references)
// and SALTUS_DECLARE/INSTANTIATE_SCHEDULE_REFINEMENT(S, Ocp) (ScheduleRefinementNlp, refine_schedule, discover_schedule and its _by_continuation).
//
// What is compiled: per scene, recover_trajectory and recover_reference of its FESD points; per
// (scene, OCP), FesdMpcc<S, Ocp> and solve_time_freezing_ocp, _from_guess and _by_continuation; per
// (scene, input law), FesdMpcc<S, Law> and simulate_time_freezing. The scene-free MPCC solver is
// compiled once in the library (saltus::timefreezing).
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hpp>
#include <saltus/timefreezing/drivers/optimal_control.hpp>
#include <saltus/timefreezing/drivers/simulate.hpp>
#include <saltus/timefreezing/recovery/recover_reference.hpp>
#include <saltus/timefreezing/recovery/recover_trajectory.hpp>
#include <saltus/timefreezing/refinement/discovery.hpp>
#include <saltus/timefreezing/refinement/refinement.hpp>

#include <vector>

/// The FESD points of scene S: FesdPoint<ny, n_switch, nu>.
#define SALTUS_DETAIL_FESD_POINTS(S)                                                                        \
  std::vector<saltus::timefreezing::FesdPoint<saltus::timefreezing::TimeFreezingSystem<S>::ny,              \
                                              saltus::timefreezing::TimeFreezingSystem<S>::n_switch, S::nu>>

#define SALTUS_TIME_FREEZING_SCENE_TEMPLATES(prefix, S)                                                          \
  prefix template saltus::HybridTrajectory<S> saltus::timefreezing::recover_trajectory<                           \
      S, saltus::timefreezing::TimeFreezingSystem<S>::ny, saltus::timefreezing::TimeFreezingSystem<S>::n_switch,  \
      S::nu>(const saltus::timefreezing::TimeFreezingSystem<S>&, const SALTUS_DETAIL_FESD_POINTS(S)&, int,        \
             const saltus::timefreezing::TrajectoryRecoveryOptions&);                                             \
  prefix template saltus::ImportedReference<S> saltus::timefreezing::recover_reference<                           \
      S, saltus::timefreezing::TimeFreezingSystem<S>::ny, saltus::timefreezing::TimeFreezingSystem<S>::n_switch,  \
      S::nu>(const saltus::HybridTrajectory<S>&, const SALTUS_DETAIL_FESD_POINTS(S)&, int, double);

#define SALTUS_TIME_FREEZING_OCP_DRIVER_TEMPLATES(prefix, S, Ocp)                                                \
  prefix template saltus::timefreezing::TimeFreezingOcpResult<S> saltus::timefreezing::solve_time_freezing_ocp<  \
      S, Ocp>(const saltus::timefreezing::TimeFreezingSystem<S>&, const Ocp&, const saltus::Vec<S::nq>&,          \
              const saltus::Vec<S::nq>&, const saltus::timefreezing::FesdOptions&,                                \
              const saltus::timefreezing::MpccSolverOptions&);                                                    \
  prefix template saltus::timefreezing::TimeFreezingOcpResult<S>                                                  \
  saltus::timefreezing::solve_time_freezing_ocp_from_guess<S, Ocp>(                                               \
      const saltus::timefreezing::TimeFreezingSystem<S>&, const Ocp&, const saltus::Vec<S::nq>&,                  \
      const saltus::Vec<S::nq>&, const saltus::timefreezing::FesdOptions&, const saltus::timefreezing::MotionGuess&, \
      const saltus::timefreezing::MpccSolverOptions&);                                                            \
  prefix template saltus::timefreezing::TimeFreezingOcpResult<S>                                                  \
  saltus::timefreezing::solve_time_freezing_ocp_by_continuation<S, Ocp>(                                          \
      const saltus::timefreezing::TimeFreezingSystem<S>&, const std::vector<Ocp>&, const Ocp&,                    \
      const saltus::Vec<S::nq>&, const saltus::Vec<S::nq>&, const saltus::timefreezing::FesdOptions&,             \
      const saltus::timefreezing::MpccSolverOptions&);

#define SALTUS_TIME_FREEZING_SIMULATION_DRIVER_TEMPLATES(prefix, S, Law)                                        \
  prefix template saltus::timefreezing::TimeFreezingSimulation<S> saltus::timefreezing::simulate_time_freezing< \
      S, Law>(const saltus::timefreezing::TimeFreezingSystem<S>&, const saltus::Vec<S::nq>&,                    \
              const saltus::Vec<S::nq>&, saltus::timefreezing::FesdOptions, const Law&,                         \
              const saltus::timefreezing::MpccSolverOptions&,                                                   \
              const saltus::timefreezing::TimeFreezingSimulationOptions&);

#define SALTUS_SCHEDULE_REFINEMENT_SCENE_TEMPLATES(prefix, S)                                              \
  prefix template std::vector<saltus::timefreezing::PhaseResimulation>                                      \
  saltus::timefreezing::resimulate_phases<S>(const S&, const saltus::HybridTrajectory<S>&,                  \
                                             const saltus::timefreezing::ModeSchedule<S::nc>&,              \
                                             const std::vector<double>&, const saltus::SimulationOptions&,  \
                                             double);                                                        \
  prefix template saltus::timefreezing::OpenLoopResimulation saltus::timefreezing::resimulate_open_loop<S>(  \
      const S&, const saltus::HybridTrajectory<S>&, const std::vector<double>&, const saltus::SimulationOptions&);

#define SALTUS_SCHEDULE_REFINEMENT_OCP_TEMPLATES(prefix, S, Ocp)                                              \
  prefix template saltus::timefreezing::RefinementResult<S> saltus::timefreezing::refine_schedule<S, Ocp>(     \
      const S&, const Ocp&, const saltus::timefreezing::OcpHorizon<S>&,                                       \
      const saltus::timefreezing::ScheduleGuess<S>&, const saltus::timefreezing::RefinementOptions&,          \
      const saltus::SimulationOptions&);                                                                      \
  prefix template saltus::timefreezing::DiscoveryResult<S> saltus::timefreezing::discover_schedule<S, Ocp>(   \
      const S&, const saltus::timefreezing::TimeFreezingSystem<S>&, const Ocp&, const saltus::Vec<S::nq>&,    \
      const saltus::Vec<S::nq>&, const saltus::timefreezing::FesdOptions&,                                    \
      const saltus::timefreezing::MpccSolverOptions&, const saltus::timefreezing::DiscoveryOptions&);  \
  prefix template saltus::timefreezing::DiscoveryResult<S> saltus::timefreezing::discover_schedule_from_guess<S, Ocp>( \
      const S&, const saltus::timefreezing::TimeFreezingSystem<S>&, const Ocp&, const saltus::Vec<S::nq>&,    \
      const saltus::Vec<S::nq>&, const saltus::timefreezing::FesdOptions&, const saltus::timefreezing::MotionGuess&, \
      const saltus::timefreezing::MpccSolverOptions&, const saltus::timefreezing::DiscoveryOptions&);  \
  prefix template saltus::timefreezing::DiscoveryResult<S>                                                    \
  saltus::timefreezing::discover_schedule_by_continuation<S, Ocp>(                                           \
      const S&, const saltus::timefreezing::TimeFreezingSystem<S>&, const std::vector<Ocp>&, const Ocp&,      \
      const saltus::Vec<S::nq>&, const saltus::Vec<S::nq>&, const saltus::timefreezing::FesdOptions&,         \
      const saltus::timefreezing::MpccSolverOptions&, const saltus::timefreezing::DiscoveryOptions&);

/// In the scene's header: the re-simulations of refined references of scene S (refinement.hpp)
/// are compiled in one .cpp elsewhere.
#define SALTUS_DECLARE_SCHEDULE_REFINEMENT_SCENE(S) SALTUS_SCHEDULE_REFINEMENT_SCENE_TEMPLATES(extern, S)
/// In the OCP's header: ScheduleRefinementNlp<S, Ocp> and refine_schedule<S, Ocp> are compiled in
/// one .cpp elsewhere (with SALTUS_DECLARE_SCHEDULE_REFINEMENT_SCENE(S) declared too).
#define SALTUS_DECLARE_SCHEDULE_REFINEMENT(S, Ocp)                           \
  extern template class saltus::timefreezing::ScheduleRefinementNlp<S, Ocp>; \
  SALTUS_SCHEDULE_REFINEMENT_OCP_TEMPLATES(extern, S, Ocp)

/// In the scene's header: the recovery of scene S is compiled in one .cpp elsewhere.
#define SALTUS_DECLARE_TIME_FREEZING_SCENE(S) SALTUS_TIME_FREEZING_SCENE_TEMPLATES(extern, S)
/// In the OCP's header: FesdMpcc<S, Ocp> and the OCP drivers are compiled in one .cpp elsewhere.
#define SALTUS_DECLARE_TIME_FREEZING_OCP(S, Ocp)            \
  extern template class saltus::timefreezing::FesdMpcc<S, Ocp>; \
  SALTUS_TIME_FREEZING_OCP_DRIVER_TEMPLATES(extern, S, Ocp)
/// In the input law's header: FesdMpcc<S, Law> and simulate_time_freezing<S, Law> are compiled
/// in one .cpp elsewhere.
#define SALTUS_DECLARE_TIME_FREEZING_SIMULATION(S, Law)     \
  extern template class saltus::timefreezing::FesdMpcc<S, Law>; \
  SALTUS_TIME_FREEZING_SIMULATION_DRIVER_TEMPLATES(extern, S, Law)
/// simulate_time_freezing<S, Law> alone, for a Law whose FesdMpcc is declared as an OCP.
#define SALTUS_DECLARE_TIME_FREEZING_SIMULATION_DRIVER(S, Law) \
  SALTUS_TIME_FREEZING_SIMULATION_DRIVER_TEMPLATES(extern, S, Law)
