// Forwarding header, kept for one release (0.2): the header moved to its stage folder.
// Include <saltus/hybrid/vocabulary/errors.hpp> instead.
#pragma once
#include <saltus/hybrid/vocabulary/errors.hpp>
