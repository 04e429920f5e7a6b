// The plank-box's time-freezing machinery, compiled once for every program of the project (see
// saltus/timefreezing/instantiate.hpp): the recovery of its FESD solutions, its simulations without
// input and under a constant input, and the flat-landing OCPs (the flagship and the short landing).
#include "scenes/plank_box_landing.hpp"

#include <saltus/timefreezing/instantiate.hxx>

SALTUS_INSTANTIATE_TIME_FREEZING_SCENE(saltus::scenes::PlankBox)
SALTUS_INSTANTIATE_TIME_FREEZING_SIMULATION(saltus::scenes::PlankBox, saltus::timefreezing::NoObjective)
SALTUS_INSTANTIATE_TIME_FREEZING_SIMULATION(saltus::scenes::PlankBox, saltus::scenes::PlankBoxConstantInput)
SALTUS_INSTANTIATE_TIME_FREEZING_OCP(saltus::scenes::PlankBox, saltus::scenes::PlankBoxFlatLanding)
SALTUS_INSTANTIATE_TIME_FREEZING_OCP(saltus::scenes::PlankBox, saltus::scenes::PlankBoxShortLanding)
