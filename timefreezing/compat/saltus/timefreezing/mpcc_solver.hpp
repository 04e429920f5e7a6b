// Forwarding header, kept for one release (0.2): the header moved to its stage folder.
// Include <saltus/timefreezing/mpcc/mpcc_solver.hpp> instead.
#pragma once
#include <saltus/timefreezing/mpcc/mpcc_solver.hpp>
