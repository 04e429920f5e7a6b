// Compiles the sensitivity machinery of the PointMass scene once (see sensitivity_instances.hpp).
#include "sensitivity_instances.hpp"

#include <saltus/sensitivity/instantiate.hxx>

SALTUS_INSTANTIATE_SCENE_SENSITIVITY(saltus::scenes::PointMass)
