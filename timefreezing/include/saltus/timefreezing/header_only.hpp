// The header-only path of saltus::timefreezing: every definition templated on a scene or an OCP
// (FesdMpcc, the simulation and optimal-control drivers, the recovery), so that the including
// translation unit compiles what it uses for its own scenes and OCPs (no
// SALTUS_DECLARE_TIME_FREEZING_OCP, no instantiation file). Simple, and slow to compile: one OCP's
// FESD MPCC and drivers cost tens of seconds per translation unit (see instantiate.hpp for compiling
// them once instead). What a header included here declares as compiled elsewhere (a scene library's
// SALTUS_DECLARE_TIME_FREEZING_*) is still linked, not compiled again. The scene-free MPCC solver
// comes from the library (saltus::timefreezing).
#pragma once

#include <saltus/timefreezing/instantiate.hxx>
