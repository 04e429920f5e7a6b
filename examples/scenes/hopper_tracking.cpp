// The hopper's tracking analysis options (declared in hopper_tracking.hpp).
#include "scenes/hopper_tracking.hpp"

#include <saltus/hybrid/dynamics/kinematics.hxx>

#include <Eigen/SVD>

#include <cmath>
#include <string>

namespace saltus::scenes {

ReferenceAnalysisOptions<Hopper> stance_start_lqr_analysis(const Hopper& hopper, const HybridTrajectory<Hopper>& reference,
                                                           int runs, double input_weight, std::ostream* progress) {
  SALTUS_REQUIRE(runs >= 0, "stance_start_lqr_analysis: runs must be >= 0, got ", runs);
  SALTUS_REQUIRE(std::isfinite(input_weight) && input_weight > 0.0,
                 "stance_start_lqr_analysis: the input weight must be finite and > 0, got ", input_weight);
  SALTUS_REQUIRE(!reference.segments.empty(), "stance_start_lqr_analysis: the reference has no segment");
  ReferenceAnalysisOptions<Hopper> o;
  o.design.name = "LQR, Q = (10 q, 1 v), R = " + std::to_string(input_weight) + " I";
  o.design.weights.Q.diagonal() << 10, 10, 10, 10, 1, 1, 1, 1;
  o.design.weights.Q_final = o.design.weights.Q;
  o.design.weights.R *= input_weight;
  const VecT<double, 8> x0 = reference.state(0, reference.t_begin());
  Kinematics<Hopper, double> kin;
  evaluate_kinematics<Hopper, double>(hopper, VecT<double, 4>(x0.head<4>()), VecT<double, 4>(x0.tail<4>()), kin);
  Eigen::Matrix<double, 3, 8> C = Eigen::Matrix<double, 3, 8>::Zero();  // gap, normal and tangential velocity
  C.block<1, 4>(0, 0) = kin.contacts[0].wn.transpose();
  C.block<1, 4>(1, 4) = kin.contacts[0].wn.transpose();
  C.block<1, 4>(2, 4) = kin.contacts[0].Wt.col(0).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix<double, 3, 8>> svd(C, Eigen::ComputeFullV);
  const Eigen::Matrix<double, 8, 5> E = svd.matrixV().rightCols<5>();
  o.stability.initial_subspace = E;
  o.monte_carlo.runs = runs;
  o.monte_carlo.threads = 1;
  o.monte_carlo.project = [E](const Vec<8>& d) { return Vec<8>(E * (E.transpose() * d)); };
  o.monte_carlo.keep_initial_contacts = true;  // the gap's curvature: hopper_tracking.hpp
  o.progress = progress;
  return o;
}

SimulationOptions hopper_monte_carlo_simulation() {
  SimulationOptions o;
  o.max_events = 2000;
  o.integrator.max_steps = 200000;
  return o;
}

}  // namespace saltus::scenes
