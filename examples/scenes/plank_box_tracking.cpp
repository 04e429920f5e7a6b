// The plank-box's tracking design and analysis options (plank_box_tracking.hpp).
#include "scenes/plank_box_tracking.hpp"

namespace saltus::scenes {

ReferenceAnalysisOptions<PlankBox> plank_box_tracking(int runs) {
  ReferenceAnalysisOptions<PlankBox> options;
  options.design.name = "LQR, box Q = (10, 1), R = 0.01 I";
  options.design.weights.Q.diagonal() << 10, 10, 10, 0, 1, 1, 1, 0;
  options.design.weights.Q_final = options.design.weights.Q;
  options.design.weights.R *= 1e-2;
  Mat<8, 8> box = Mat<8, 8>::Zero();
  Eigen::Matrix<double, 8, Eigen::Dynamic, 0, 8, 8> E = Eigen::Matrix<double, 8, 6>::Zero();
  int c = 0;
  for (int k : {0, 1, 2, 4, 5, 6}) {  // x, y, theta and their rates; not the plank's phi, phi'
    box(k, k) = 1.0;
    E(k, c++) = 1.0;
  }
  options.stability.output_weight = box;
  options.stability.initial_subspace = E;
  options.monte_carlo.runs = runs;
  options.monte_carlo.output_weight = box;
  options.monte_carlo.scale << 1, 1, 1, 0, 1, 1, 1, 0;
  return options;
}

}  // namespace saltus::scenes
