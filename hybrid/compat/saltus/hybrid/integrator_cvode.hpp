// Forwarding header, kept for one release (0.2): the header moved to its stage folder.
// Include <saltus/hybrid/simulation/integrator_cvode.hpp> instead.
#pragma once
#include <saltus/hybrid/simulation/integrator_cvode.hpp>
