// Forwarding header at the 0.1 path <saltus/timefreezing/mpcc.hpp>, kept for 0.2 only (CHANGELOG.md, 0.2.0).
// The deprecation note never fails a -Werror build (saltus/compat/definitions_0_1.hpp says how);
// defining SALTUS_NO_DEPRECATED_HEADER_MESSAGES silences it.
#pragma once
#if !defined(SALTUS_NO_DEPRECATED_HEADER_MESSAGES)
#if defined(__clang__)
#pragma clang diagnostic push
#pragma clang diagnostic warning "-W#warnings"
#warning "saltus: <saltus/timefreezing/mpcc.hpp> is deprecated (the 0.1 path, removed after 0.2): include <saltus/timefreezing/mpcc/mpcc.hpp>"
#pragma clang diagnostic pop
#else
#pragma message("saltus: <saltus/timefreezing/mpcc.hpp> is deprecated (the 0.1 path, removed after 0.2): include <saltus/timefreezing/mpcc/mpcc.hpp>")
#endif
#endif
#include <saltus/timefreezing/mpcc/mpcc.hpp>
