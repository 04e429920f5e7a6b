// The hopper's mode-schedule refinement, compiled once (hopper_holes_refinement.hpp).
#include "scenes/hopper_holes_refinement.hpp"

#include <saltus/timefreezing/instantiate.hxx>

SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT_SCENE(saltus::scenes::Hopper)
SALTUS_INSTANTIATE_SCHEDULE_REFINEMENT(saltus::scenes::Hopper, saltus::scenes::HopperOverThreeHoles)
