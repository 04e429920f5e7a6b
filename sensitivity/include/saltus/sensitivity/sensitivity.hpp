// saltus::sensitivity in one include: jump gains (thesis C.37-C.39) and their numerical twin,
// the linearised time-triggered hybrid system, the first-order prediction and its check against
// re-simulation, the reference-spreading tracking design and its stability check, and the analysis
// of a reference in one call with its JSON writer.
#pragma once

#include <saltus/sensitivity/analysis/reference_analysis.hpp>
#include <saltus/sensitivity/analysis/reference_analysis_io.hpp>
#include <saltus/sensitivity/conewise_gain.hpp>
#include <saltus/sensitivity/jump_gain.hpp>
#include <saltus/sensitivity/linearisation.hpp>
#include <saltus/sensitivity/numerical_jump_gain.hpp>
#include <saltus/sensitivity/prediction_check.hpp>
#include <saltus/sensitivity/tracking.hpp>
