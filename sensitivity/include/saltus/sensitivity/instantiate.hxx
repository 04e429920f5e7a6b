// The definitions of saltus::sensitivity and the macro that compiles them for one scene (see
// instantiate.hpp).
#pragma once

#include <saltus/sensitivity/instantiate.hpp>
#include <saltus/sensitivity/analysis/reference_analysis.hxx>
#include <saltus/sensitivity/conewise_gain.hxx>
#include <saltus/sensitivity/jump_gain.hxx>
#include <saltus/sensitivity/linearisation.hxx>
#include <saltus/sensitivity/numerical_jump_gain.hxx>
#include <saltus/sensitivity/prediction_check.hxx>
#include <saltus/sensitivity/tracking.hxx>

/// Everything SALTUS_SENSITIVITY_TEMPLATES lists (instantiate.hpp), for scene S.
#define SALTUS_INSTANTIATE_SCENE_SENSITIVITY(S) SALTUS_SENSITIVITY_TEMPLATES(, S)
