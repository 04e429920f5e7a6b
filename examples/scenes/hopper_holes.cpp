// The hopper's time-freezing machinery, compiled once for every program of the project (see
// saltus/timefreezing/instantiate.hpp): the recovery of its FESD solutions and the OCPs over three
// holes and over one.
#include "scenes/hopper_holes.hpp"

#include <saltus/timefreezing/instantiate.hxx>

SALTUS_INSTANTIATE_TIME_FREEZING_SCENE(saltus::scenes::Hopper)
SALTUS_INSTANTIATE_TIME_FREEZING_OCP(saltus::scenes::Hopper, saltus::scenes::HopperOverThreeHoles)
SALTUS_INSTANTIATE_TIME_FREEZING_OCP(saltus::scenes::Hopper, saltus::scenes::HopperOverOneHole)
