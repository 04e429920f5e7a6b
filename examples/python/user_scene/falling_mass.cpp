// FallingMass's machinery (simulation, jump gains, tracking), compiled once for the extension.
#include "falling_mass.hpp"

#include <saltus/hybrid/instantiate.hxx>
#include <saltus/sensitivity/instantiate.hxx>

SALTUS_INSTANTIATE_SCENE(FallingMass)
SALTUS_INSTANTIATE_SCENE_SENSITIVITY(FallingMass)
