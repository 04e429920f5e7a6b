// The definitions of every scene-templated algorithm of saltus::hybrid and the macros that
// compile them for one scene, in one .cpp per scene (see instantiate.hpp for the pattern).
#pragma once

#include <saltus/hybrid/instantiate.hpp>

#include <saltus/hybrid/dynamics/constraints.hxx>
#include <saltus/hybrid/dynamics/derivatives.hxx>
#include <saltus/hybrid/dynamics/flow.hxx>
#include <saltus/hybrid/dynamics/impact.hxx>
#include <saltus/hybrid/dynamics/jump_map.hxx>
#include <saltus/hybrid/dynamics/kinematics.hxx>
#include <saltus/hybrid/dynamics/mode_selection.hxx>
#include <saltus/hybrid/reference/reference_spreading.hxx>
#include <saltus/hybrid/reference/resimulation.hxx>
#if defined(SALTUS_WITH_CVODE) && SALTUS_WITH_CVODE
#include <saltus/hybrid/simulation/integrator_cvode.hxx>  // the optional component saltus::cvode
#endif
#include <saltus/hybrid/simulation/integrator_dopri.hxx>
#include <saltus/hybrid/simulation/mode_system.hxx>
#include <saltus/hybrid/simulation/simulator.hxx>
#include <saltus/hybrid/simulation/transition.hxx>

/// The double-precision kernels, the impact solver and the mode selector of scene S.
#define SALTUS_INSTANTIATE_SCENE_DYNAMICS(S) SALTUS_HYBRID_DYNAMICS_TEMPLATES(, S)
/// The kernels on dual numbers and the flow, guard and jump-map Jacobians of scene S.
#define SALTUS_INSTANTIATE_SCENE_DERIVATIVES(S) SALTUS_HYBRID_DERIVATIVE_TEMPLATES(, S)
/// The mode system, the integrators, the event physics, the simulator, reference spreading and
/// polish of scene S.
#define SALTUS_INSTANTIATE_SCENE_SIMULATION(S) SALTUS_HYBRID_SIMULATION_TEMPLATES(, S)
/// All of saltus::hybrid for scene S, in one translation unit.
#define SALTUS_INSTANTIATE_SCENE(S)      \
  SALTUS_INSTANTIATE_SCENE_DYNAMICS(S)   \
  SALTUS_INSTANTIATE_SCENE_DERIVATIVES(S) \
  SALTUS_INSTANTIATE_SCENE_SIMULATION(S)
