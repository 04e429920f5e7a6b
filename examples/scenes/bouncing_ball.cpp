// The BouncingBall scene's machinery, compiled once for every program of the project (see
// saltus/hybrid/instantiate.hpp): simulation, derivatives, reference spreading and sensitivity.
#include "scenes/bouncing_ball.hpp"

#include <saltus/hybrid/instantiate.hxx>
#include <saltus/sensitivity/instantiate.hxx>

SALTUS_INSTANTIATE_SCENE(saltus::scenes::BouncingBall)
SALTUS_INSTANTIATE_SCENE_SENSITIVITY(saltus::scenes::BouncingBall)
