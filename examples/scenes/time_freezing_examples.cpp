// The point mass's time-freezing machinery, compiled once for every program of the project (see
// saltus/timefreezing/instantiate.hpp): the recovery of its FESD solutions, its simulations without
// input (the frictional landing) and under the guiding example's input law, and the OCP that lands
// and slides it to a target.
#include "scenes/time_freezing_examples.hpp"

#include <saltus/timefreezing/instantiate.hxx>

SALTUS_INSTANTIATE_TIME_FREEZING_SCENE(saltus::scenes::PointMass)
SALTUS_INSTANTIATE_TIME_FREEZING_SIMULATION(saltus::scenes::PointMass, saltus::timefreezing::NoObjective)
SALTUS_INSTANTIATE_TIME_FREEZING_SIMULATION(saltus::scenes::PointMass, saltus::scenes::Example3)
SALTUS_INSTANTIATE_TIME_FREEZING_OCP(saltus::scenes::PointMass, saltus::scenes::PointMassToTheTarget)
