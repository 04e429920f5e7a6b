// The SpatialBox scene's machinery, compiled once for every program of the project (see
// saltus/hybrid/instantiate.hpp): simulation, derivatives, reference spreading and sensitivity.
#include "scenes/spatial_box.hpp"

#include <saltus/hybrid/instantiate.hxx>
#include <saltus/sensitivity/instantiate.hxx>

SALTUS_INSTANTIATE_SCENE(saltus::scenes::SpatialBox)
SALTUS_INSTANTIATE_SCENE_SENSITIVITY(saltus::scenes::SpatialBox)
