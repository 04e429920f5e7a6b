// Forwarding header, kept for one release (0.2): the header moved to its stage folder.
// Include <saltus/timefreezing/formulation/time_freezing_system.hpp> instead.
#pragma once
#include <saltus/timefreezing/formulation/time_freezing_system.hpp>
