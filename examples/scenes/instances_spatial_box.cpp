// Compiles the simulation machinery of the spatial_box scene once (see instances.hpp).
#include "scenes/instances.hpp"

SALTUS_SCENE_INSTANCES(, saltus::scenes::SpatialBox)
