// Compiles the simulation machinery of the point_mass scene once (see instances.hpp).
#include "scenes/instances.hpp"

SALTUS_SCENE_INSTANCES(, saltus::scenes::PointMass)
