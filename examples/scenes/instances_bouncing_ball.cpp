// Compiles the simulation machinery of the bouncing_ball scene once (see instances.hpp).
#include "scenes/instances.hpp"

SALTUS_SCENE_INSTANCES(, saltus::scenes::BouncingBall)
