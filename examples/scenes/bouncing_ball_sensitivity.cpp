// The BouncingBall scene's sensitivity machinery (jump gains, conewise gains, linearisation,
// tracking design and stability check), compiled once for every program of the project (see
// saltus/sensitivity/instantiate.hpp); its hybrid machinery is in bouncing_ball.cpp.
#include "scenes/bouncing_ball.hpp"

#include <saltus/hybrid/instantiate.hxx>
#include <saltus/sensitivity/instantiate.hxx>

SALTUS_INSTANTIATE_SCENE_SENSITIVITY(saltus::scenes::BouncingBall)
