// The mode-schedule refinement of the hopper over three holes (refine_schedule, discover_schedule
// and discover_schedule_by_continuation for scenes::HopperOverThreeHoles), declared here and
// compiled once in hopper_holes_refinement.cpp, in its own library saltus_hopper_refinement: only
// the programs that refine the hopper (examples/hopper.cpp --json, bench/experiments) link it, so
// the tests' scene library does not compile it.
#pragma once

#include "scenes/hopper_holes.hpp"

#include <saltus/timefreezing/refinement/discovery.hpp>
#include <saltus/timefreezing/refinement/refinement.hpp>

SALTUS_DECLARE_SCHEDULE_REFINEMENT_SCENE(saltus::scenes::Hopper)
SALTUS_DECLARE_SCHEDULE_REFINEMENT(saltus::scenes::Hopper, saltus::scenes::HopperOverThreeHoles)
