// Forwarding header at the 0.1 path <saltus/hybrid/contact_problem.hpp>, kept for 0.2 only (CHANGELOG.md, 0.2.0).
// The deprecation note never fails a -Werror build (saltus/compat/definitions_0_1.hpp says how);
// defining SALTUS_NO_DEPRECATED_HEADER_MESSAGES silences it.
#pragma once
#if !defined(SALTUS_NO_DEPRECATED_HEADER_MESSAGES)
#if defined(__clang__)
#pragma clang diagnostic push
#pragma clang diagnostic warning "-W#warnings"
#warning "saltus: <saltus/hybrid/contact_problem.hpp> is deprecated (the 0.1 path, removed after 0.2): include <saltus/hybrid/contact/contact_problem.hpp>"
#pragma clang diagnostic pop
#else
#pragma message("saltus: <saltus/hybrid/contact_problem.hpp> is deprecated (the 0.1 path, removed after 0.2): include <saltus/hybrid/contact/contact_problem.hpp>")
#endif
#endif
#include <saltus/hybrid/contact/contact_problem.hpp>
