// Compiles the machinery of FallingMass once: its simulation (saltus::hybrid) and its analyses
// (saltus::sensitivity), for every program of this project.
#include "falling_mass.hpp"

#include <saltus/hybrid/instantiate.hxx>
#include <saltus/sensitivity/instantiate.hxx>

SALTUS_INSTANTIATE_SCENE(FallingMass)
SALTUS_INSTANTIATE_SCENE_SENSITIVITY(FallingMass)
