// Compiles the sensitivity machinery of the hopper scene once (see sensitivity_instances.hpp).
#include "sensitivity_instances.hpp"

SALTUS_SENSITIVITY_INSTANCES(, saltus::scenes::Hopper)
