// Forwarding header, kept for one release (0.2): the header moved to its stage folder.
// Include <saltus/timefreezing/drivers/optimal_control.hpp> (declarations) or
// <saltus/timefreezing/header_only.hpp> (definitions) instead.
#pragma once
#include <saltus/timefreezing/header_only.hpp>
