// The mode-schedule refinement of the plank-box flat landing and of its short landing, compiled once for the scene library (its own
// translation unit, so that it builds beside the time-freezing instantiations).
#include "scenes/plank_box_landing.hpp"

#include <saltus/timefreezing/instantiate.hxx>

SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT_SCENE(saltus::scenes::PlankBox)
SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT(saltus::scenes::PlankBox, saltus::scenes::PlankBoxFlatLanding)
SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT(saltus::scenes::PlankBox, saltus::scenes::PlankBoxShortLanding)
