// The header-only path: every definition of saltus::hybrid, so that the including translation
// unit compiles what it uses for its own scenes (no SALTUS_DECLARE_SCENE, no instantiation file).
// Simple, and slow to compile: a scene's full machinery costs tens of seconds per translation unit
// (see instantiate.hpp for compiling it once instead). The scene-free contact numerics still come
// from the library (saltus::hybrid).
#pragma once

#include <saltus/hybrid/instantiate.hxx>
