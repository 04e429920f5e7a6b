// The definitions that 0.1's headers carried, for the forwarding headers at the 0.1 paths
// (kept for 0.2 only; CHANGELOG.md, 0.2.0). In 0.1 every header defined what it declared; since
// 0.2 the scene-templated algorithms are declared in .hpp and defined in .hxx, compiled once per
// scene (SALTUS_INSTANTIATE_SCENE) or in every file that includes header_only.hpp. A forwarding
// header that declares such algorithms includes this one, so that a 0.1 program with a scene of
// its own and no instantiation macro compiles and links as it did.
//
// The sensitivity headers kept their 0.1 paths (jump_gain.hpp, linearisation.hpp,
// numerical_jump_gain.hpp, sensitivity.hpp) and now declare only: their definitions come here
// too, where they are installed, so that a 0.1 program that includes one old hybrid path gets
// them (a file that includes sensitivity headers only, and no old path, links them from a scene's
// instantiation: SALTUS_INSTANTIATE_SCENE_SENSITIVITY, or includes
// <saltus/sensitivity/header_only.hpp>). Parsing them costs about 1.5 s per file; nothing of
// them is compiled unless used, and using them needs saltus::sensitivity linked, as in 0.1.
//
// No duplicate symbols: where a scene's header declares its templates extern
// (SALTUS_DECLARE_SCENE...), the definitions here emit no symbol for it and the program
// links the scene library's explicit instantiations; elsewhere the implicit instantiations are
// emitted as mergeable (COMDAT) symbols, as the explicit ones are. Each header is #pragma once,
// so old and new paths mix in one file.
//
// The deprecation note of each forwarding header names the new path. It must reach the user and
// must not fail a -Werror build: GCC gets #pragma message, a note (never an error, printed from a
// system include directory too, which is how CMake passes an imported target's directories);
// clang gets #warning inside a diagnostic push that maps -W#warnings to a warning, which clang
// prints from system headers as well and does not promote under -Werror (clang's own
// #pragma message is not printed from a system header). Measured with GCC 12.2 and clang 14
// (-Wall -Wextra -Wpedantic -Werror, -Weverything -Werror, -pedantic-errors). Defining
// SALTUS_NO_DEPRECATED_HEADER_MESSAGES silences it in both.
#pragma once

#include <saltus/hybrid/header_only.hpp>
#if __has_include(<saltus/sensitivity/header_only.hpp>)
#include <saltus/sensitivity/header_only.hpp>
#endif
