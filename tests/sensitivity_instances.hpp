// The sensitivity machinery of the scenes the sensitivity tests and the jump-gain benchmark use,
// compiled once (sensitivity_instances_<scene>.cpp, library saltus_sensitivity_instances) and
// declared extern here, as examples/scenes/instances.hpp does for the hybrid machinery.
#pragma once

#include "scenes/instances.hpp"

#include <saltus/sensitivity/instantiate.hpp>
#include <saltus/sensitivity/sensitivity.hpp>

SALTUS_DECLARE_SCENE_SENSITIVITY(saltus::scenes::PointMass)
SALTUS_DECLARE_SCENE_SENSITIVITY(saltus::scenes::Hopper)
SALTUS_DECLARE_SCENE_SENSITIVITY(saltus::scenes::PlankBox)
