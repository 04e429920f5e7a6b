// The SpatialBox scene's machinery, compiled once for every program of the project (see
// saltus/hybrid/instantiate.hpp): simulation, derivatives and reference spreading; its
// sensitivity machinery is in spatial_box_sensitivity.cpp (two files: they compile in parallel, and
// a change to one module recompiles only its half).
#include "scenes/spatial_box.hpp"

#include <saltus/hybrid/instantiate.hxx>

SALTUS_INSTANTIATE_SCENE(saltus::scenes::SpatialBox)
