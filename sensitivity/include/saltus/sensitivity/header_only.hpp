// The header-only path of saltus::sensitivity: every definition, compiled in the including
// translation unit (see instantiate.hpp for compiling a scene's machinery once instead).
#pragma once

#include <saltus/hybrid/header_only.hpp>
#include <saltus/sensitivity/instantiate.hxx>
