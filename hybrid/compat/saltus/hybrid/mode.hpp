// Forwarding header, kept for one release (0.2): the header moved to its stage folder.
// Include <saltus/hybrid/vocabulary/mode.hpp> instead.
#pragma once
#include <saltus/hybrid/vocabulary/mode.hpp>
