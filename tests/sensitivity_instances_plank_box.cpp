// Compiles the sensitivity machinery of the plank_box scene once (see sensitivity_instances.hpp).
#include "sensitivity_instances.hpp"

SALTUS_SENSITIVITY_INSTANCES(, saltus::scenes::PlankBox)
