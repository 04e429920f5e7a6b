// The sensitivity machinery of the scenes the sensitivity tests and the jump-gain benchmark use,
// compiled once (sensitivity_instances_<scene>.cpp, library saltus_sensitivity_instances) and
// declared extern here, as examples/scenes/instances.hpp does for the simulation machinery.
#pragma once

#include "scenes/instances.hpp"

#include <saltus/sensitivity/sensitivity.hpp>

#define SALTUS_SENSITIVITY_INSTANCES(prefix, Scene)                                                        \
  prefix template class saltus::JumpGainSolver<Scene>;                                                     \
  prefix template class saltus::LinearisedSystem<Scene>;                                                   \
  prefix template saltus::NumericalJumpGain<Scene> saltus::numerical_jump_gain<Scene>(                              \
      const Scene&, const saltus::HybridTrajectory<Scene>&, int, const saltus::NumericalJumpGainOptions&);

SALTUS_SENSITIVITY_INSTANCES(extern, saltus::scenes::PointMass)
SALTUS_SENSITIVITY_INSTANCES(extern, saltus::scenes::Hopper)
SALTUS_SENSITIVITY_INSTANCES(extern, saltus::scenes::PlankBox)
