// Compiles the simulation machinery of the hopper scene once (see instances.hpp).
#include "scenes/instances.hpp"

SALTUS_SCENE_INSTANCES(, saltus::scenes::Hopper)
