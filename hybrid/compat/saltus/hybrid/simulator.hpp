// Forwarding header, kept for one release (0.2): the header moved to its stage folder, and
// polish() and reference spreading to reference/. Include <saltus/hybrid/simulation/simulator.hpp>
// and <saltus/hybrid/reference/resimulation.hpp> instead.
#pragma once
#include <saltus/hybrid/reference/reference_spreading.hpp>
#include <saltus/hybrid/reference/resimulation.hpp>
#include <saltus/hybrid/simulation/simulator.hpp>
#include <saltus/hybrid/vocabulary/trajectory_io.hpp>
