// Compiles the machinery of the Hopper scene once (see instances.hpp).
#include "scenes/instances.hpp"

#include <saltus/hybrid/instantiate.hxx>

SALTUS_INSTANTIATE_SCENE(saltus::scenes::Hopper)
