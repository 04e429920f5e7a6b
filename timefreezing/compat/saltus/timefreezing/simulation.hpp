// Forwarding header at the 0.1 path <saltus/timefreezing/simulation.hpp>, kept for 0.2 only (CHANGELOG.md, 0.2.0).
// As 0.1's header did, it also defines the scene-templated algorithms (the header-only path),
// so that a 0.1 program with a scene of its own and no instantiation macro compiles and links.
// The deprecation note never fails a -Werror build (saltus/compat/definitions_0_1.hpp says how);
// defining SALTUS_NO_DEPRECATED_HEADER_MESSAGES silences it.
#pragma once
#if !defined(SALTUS_NO_DEPRECATED_HEADER_MESSAGES)
#if defined(__clang__)
#pragma clang diagnostic push
#pragma clang diagnostic warning "-W#warnings"
#warning "saltus: <saltus/timefreezing/simulation.hpp> is deprecated (the 0.1 path, removed after 0.2): include <saltus/timefreezing/drivers/optimal_control.hpp> and instantiate the scene once, or include <saltus/timefreezing/header_only.hpp> (CHANGELOG.md, 0.2.0)"
#pragma clang diagnostic pop
#else
#pragma message("saltus: <saltus/timefreezing/simulation.hpp> is deprecated (the 0.1 path, removed after 0.2): include <saltus/timefreezing/drivers/optimal_control.hpp> and instantiate the scene once, or include <saltus/timefreezing/header_only.hpp> (CHANGELOG.md, 0.2.0)")
#endif
#endif
#include <saltus/timefreezing/drivers/simulate.hpp>
#include <saltus/timefreezing/drivers/optimal_control.hpp>
#include <saltus/compat/definitions_0_1.hpp>  // every definition, as 0.1
#include <saltus/timefreezing/header_only.hpp>
