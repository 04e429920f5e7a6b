// The tracking design of a plank-box reference and what its analysis measures
// (saltus/sensitivity/analysis/reference_analysis.hpp), shared by `plank_box --json` (the optimised
// flat landing), tracking_stability (its plank-box case) and tests/test_flagship_ocps.cpp: a
// time-varying LQR with the box's coordinates weighted (Q = 10 on its position and angle, 1 on
// their rates; the plank has no actuator and no weight), R = 0.01 I, Q_final = Q; deviations of
// the box's initial state only (the plank starts at rest), measured on the box (a semi-norm: W_out
// is the box's block), in the check and in the Monte Carlo batch alike.
#pragma once

#include "scenes/plank_box.hpp"

#include <saltus/sensitivity/analysis/reference_analysis.hpp>

namespace saltus::scenes {

/// The options above with `runs` closed-loop runs of perturbation size 1e-4 (MonteCarloOptions'
/// default size); spreading 0.02 s (the default); silent (no progress stream).
ReferenceAnalysisOptions<PlankBox> plank_box_tracking(int runs);

}  // namespace saltus::scenes
