// Compiles the machinery of Puck and PuckToTheMark once (puck.hpp): simulation, analyses, the
// time-freezing OCP and its mode-schedule refinement.
#include "puck.hpp"

#include <saltus/hybrid/instantiate.hxx>
#include <saltus/sensitivity/instantiate.hxx>
#include <saltus/timefreezing/instantiate.hxx>

SALTUS_INSTANTIATE_SCENE(Puck)
SALTUS_INSTANTIATE_SCENE_SENSITIVITY(Puck)
SALTUS_INSTANTIATE_TIME_FREEZING_SCENE(Puck)
SALTUS_INSTANTIATE_TIME_FREEZING_OCP(Puck, PuckToTheMark)
SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT_SCENE(Puck)
SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT(Puck, PuckToTheMark)
