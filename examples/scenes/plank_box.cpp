// The PlankBox scene's machinery, compiled once for every program of the project (see
// saltus/hybrid/instantiate.hpp): simulation, derivatives, reference spreading and sensitivity.
#include "scenes/plank_box.hpp"

#include <saltus/hybrid/instantiate.hxx>
#include <saltus/sensitivity/instantiate.hxx>

SALTUS_INSTANTIATE_SCENE(saltus::scenes::PlankBox)
SALTUS_INSTANTIATE_SCENE_SENSITIVITY(saltus::scenes::PlankBox)
