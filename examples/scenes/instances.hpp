// The simulation machinery of every example scene, compiled once: instantiated in
// instances_<scene>.cpp (library saltus_scenes) and declared extern here, so a test or program
// that includes this header does not compile it again.
#pragma once

#include "scenes/all_scenes.hpp"

#include <saltus/hybrid/instantiate.hpp>

SALTUS_DECLARE_SCENE(saltus::scenes::PointMass)
SALTUS_DECLARE_SCENE(saltus::scenes::BouncingBall)
SALTUS_DECLARE_SCENE(saltus::scenes::PlankBox)
SALTUS_DECLARE_SCENE(saltus::scenes::Hopper)
SALTUS_DECLARE_SCENE(saltus::scenes::SpatialBox)
