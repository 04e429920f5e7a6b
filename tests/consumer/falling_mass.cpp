// Compiles the simulation machinery of FallingMass once.
#include "falling_mass.hpp"

#include <saltus/hybrid/instantiate.hxx>

SALTUS_INSTANTIATE_SCENE(FallingMass)
