// The Hopper scene's sensitivity machinery (jump gains, conewise gains, linearisation,
// tracking design and stability check), compiled once for every program of the project (see
// saltus/sensitivity/instantiate.hpp); its hybrid machinery is in hopper.cpp.
#include "scenes/hopper.hpp"

#include <saltus/hybrid/instantiate.hxx>
#include <saltus/sensitivity/instantiate.hxx>

SALTUS_INSTANTIATE_SCENE_SENSITIVITY(saltus::scenes::Hopper)
