// The simulation machinery of every example scene, compiled once: the templates below are
// instantiated in instances_<scene>.cpp (library saltus_scenes) and declared extern here, so a
// test or program that includes this header does not compile them again (each costs 30-50 s).
#pragma once

#include "scenes/all_scenes.hpp"

#include <saltus/hybrid/reference/reference_spreading.hpp>
#include <saltus/hybrid/simulation/simulator.hpp>

#define SALTUS_SCENE_INSTANCES(prefix, Scene)                  \
  prefix template class saltus::Simulator<Scene>;              \
  prefix template class saltus::ImpactSolver<Scene>;           \
  prefix template class saltus::ModeSelector<Scene>;           \
  prefix template class saltus::ModeSystem<Scene>;             \
  prefix template class saltus::DormandPrinceIntegrator<Scene>; \
  prefix template class saltus::CvodeIntegrator<Scene>;       \
  prefix template class saltus::ExtendedReference<Scene>;

SALTUS_SCENE_INSTANCES(extern, saltus::scenes::PointMass)
SALTUS_SCENE_INSTANCES(extern, saltus::scenes::BouncingBall)
SALTUS_SCENE_INSTANCES(extern, saltus::scenes::PlankBox)
SALTUS_SCENE_INSTANCES(extern, saltus::scenes::Hopper)
SALTUS_SCENE_INSTANCES(extern, saltus::scenes::SpatialBox)
