// Temporary: the CVODE backend is being split into .hpp/.hxx.
#pragma once
#include <saltus/hybrid/simulation/integrator_cvode.hpp>
