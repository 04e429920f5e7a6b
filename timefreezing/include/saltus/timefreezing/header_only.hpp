// The header-only path of saltus::timefreezing: every definition templated on a scene or an OCP
// (the FESD MPCC, the simulation and optimal-control drivers), so that the including translation
// unit compiles what it uses for its own scenes and OCPs (no SALTUS_DECLARE_TIME_FREEZING_OCP, no
// instantiation file). Simple, and slow to compile: one OCP's FESD MPCC and drivers cost tens of
// seconds per translation unit. The scene-free MPCC solver still comes from the library
// (saltus::timefreezing).
#pragma once

#include <saltus/timefreezing/drivers/optimal_control.hxx>
#include <saltus/timefreezing/drivers/simulate.hxx>
