// The tracking design of the plank-box's optimised landing and what its analysis measures
// (ocp_analysis.hpp), shared by `plank_box --json`, tracking_stability (its plank-box case) and
// tests/test_flagship_ocps.cpp: the box's coordinates weighted (Q = 10 on its
// position and angle, 1 on their rates; the plank has no actuator and no weight), R = 0.01 I,
// Q_final = Q; deviations of the box's initial state only (the plank starts at rest), measured on
// the box (a semi-norm: W_out is the box's block).
#pragma once

#include "ocp_analysis.hpp"
#include "scenes/plank_box.hpp"

namespace saltus::examples {

/// `runs` closed-loop runs of perturbation size 1e-4 (MonteCarloOptions' default size).
inline ReferenceAnalysisSetup<scenes::PlankBox> plank_box_tracking_setup(int runs) {
  ReferenceAnalysisSetup<scenes::PlankBox> setup;
  setup.design = "LQR, box Q = (10, 1), R = 0.01 I";
  setup.weights.Q.diagonal() << 10, 10, 10, 0, 1, 1, 1, 0;
  setup.weights.Q_final = setup.weights.Q;
  setup.weights.R *= 1e-2;
  Mat<8, 8> box = Mat<8, 8>::Zero();
  Eigen::Matrix<double, 8, Eigen::Dynamic, 0, 8, 8> E = Eigen::Matrix<double, 8, 6>::Zero();
  int c = 0;
  for (int k : {0, 1, 2, 4, 5, 6}) {  // x, y, theta and their rates; not the plank's phi, phi'
    box(k, k) = 1.0;
    E(k, c++) = 1.0;
  }
  setup.check.output_weight = box;
  setup.check.initial_subspace = E;
  setup.monte_carlo.runs = runs;
  setup.monte_carlo.output_weight = box;
  setup.monte_carlo.scale << 1, 1, 1, 0, 1, 1, 1, 0;
  return setup;
}

}  // namespace saltus::examples
