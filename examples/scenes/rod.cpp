// The rod's machinery, compiled once (rod.hpp).
#include "scenes/rod.hpp"

#include <saltus/hybrid/instantiate.hxx>
#include <saltus/timefreezing/instantiate.hxx>

SALTUS_INSTANTIATE_SCENE(saltus::scenes::Rod)
SALTUS_INSTANTIATE_TIME_FREEZING_SCENE(saltus::scenes::Rod)
SALTUS_INSTANTIATE_TIME_FREEZING_SIMULATION(saltus::scenes::Rod, saltus::timefreezing::NoObjective)
