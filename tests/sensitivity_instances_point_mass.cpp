// Compiles the sensitivity machinery of the point_mass scene once (see sensitivity_instances.hpp).
#include "sensitivity_instances.hpp"

SALTUS_SENSITIVITY_INSTANCES(, saltus::scenes::PointMass)
