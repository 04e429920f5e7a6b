// Forwarding header, kept for one release (0.2): the header moved to its stage folder and was
// split into a declaration (integrator_cvode.hpp) and the member definitions
// (integrator_cvode.hxx). As in 0.1, this path gives both: include
// <saltus/hybrid/simulation/integrator_cvode.hpp> (or .hxx where CvodeIntegrator is instantiated) instead.
#pragma once
#include <saltus/hybrid/simulation/integrator_cvode.hxx>
