// The mode-schedule refinement of the guiding example's OCP (PointMassToTheTarget), compiled once for the scene library (its own
// translation unit, so that it builds beside the time-freezing instantiations).
#include "scenes/time_freezing_examples.hpp"

#include <saltus/timefreezing/instantiate.hxx>

SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT_SCENE(saltus::scenes::PointMass)
SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT(saltus::scenes::PointMass, saltus::scenes::PointMassToTheTarget)
