// Forwarding header, kept for one release (0.2): the header moved to its stage folder and its
// definitions into .hxx pieces. Include <saltus/timefreezing/discretisation/fesd.hpp> (declarations)
// or <saltus/timefreezing/header_only.hpp> (definitions) instead.
#pragma once
#include <saltus/timefreezing/header_only.hpp>
