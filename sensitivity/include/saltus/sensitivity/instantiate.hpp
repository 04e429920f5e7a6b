// Compile a scene's sensitivity machinery once, as saltus/hybrid/instantiate.hpp does for the
// hybrid machinery (see there for the pattern):
//
//   // my_scene.hpp, after SALTUS_DECLARE_SCENE(MyScene):
//   #include <saltus/sensitivity/instantiate.hpp>
//   SALTUS_DECLARE_SCENE_SENSITIVITY(MyScene)
//
//   // my_scene_sensitivity.cpp (or the scene's one instantiation file):
//   #include "my_scene.hpp"
//   #include <saltus/sensitivity/instantiate.hxx>
//   SALTUS_INSTANTIATE_SCENE_SENSITIVITY(MyScene)
//
// Compiled per scene: feedback_gain, JumpGainSolver, jump_gains, ConewiseJumpGain, LinearisedSystem,
// numerical_jump_gain, numerical_conewise_piece, prediction_remainder, piece_remainder, and the
// tracking design and stability check (GainSchedule, lqr_design, ReferenceSpreadingController, ClosedLoopLinearisation,
// check_stability, check_periodic_stability, monte_carlo), and the analysis of a reference in one call
// (analyse_reference). The hybrid machinery they call must be instantiated too
// (SALTUS_INSTANTIATE_SCENE). <saltus/sensitivity/header_only.hpp> is the header-only path.
#pragma once

#include <saltus/sensitivity/analysis/reference_analysis.hpp>
#include <saltus/sensitivity/conewise_gain.hpp>
#include <saltus/sensitivity/jump_gain.hpp>
#include <saltus/sensitivity/linearisation.hpp>
#include <saltus/sensitivity/numerical_jump_gain.hpp>
#include <saltus/sensitivity/prediction_check.hpp>
#include <saltus/sensitivity/tracking.hpp>

#define SALTUS_SENSITIVITY_TEMPLATES(prefix, S)                                                                  \
  prefix template void saltus::feedback_gain<S>(const saltus::InputLaw<S>&, double, const saltus::Vec<2 * S::nq>&, \
                                                const saltus::Mode<S::nc>&, double, saltus::Vec<2 * S::nq>&,     \
                                                saltus::Mat<S::nu, 2 * S::nq>&);                                 \
  prefix template class saltus::JumpGainSolver<S>;                                                               \
  prefix template std::vector<saltus::JumpGain<S>> saltus::jump_gains<S>(                                        \
      const S&, const saltus::HybridTrajectory<S>&, const saltus::JumpGainOptions&);                             \
  prefix template struct saltus::ConewisePiece<S>;                                                               \
  prefix template class saltus::ConewiseJumpGain<S>;                                                             \
  prefix template class saltus::LinearisedSystem<S>;                                                             \
  prefix template saltus::NumericalJumpGain<S> saltus::numerical_jump_gain<S>(                                   \
      const S&, const saltus::HybridTrajectory<S>&, int, const saltus::NumericalJumpGainOptions&);             \
  prefix template struct saltus::NumericalConewisePiece<S>;                                                      \
  prefix template saltus::NumericalConewisePiece<S> saltus::numerical_conewise_piece<S>(                         \
      const S&, const saltus::HybridTrajectory<S>&, int, const saltus::ConewisePiece<S>&,                        \
      const saltus::NumericalJumpGainOptions&);                                                                  \
  prefix template saltus::RemainderFit saltus::prediction_remainder<S>(                                          \
      const saltus::LinearisedSystem<S>&, const saltus::SimulationOptions&, const saltus::Vec<2 * S::nq>&,       \
      const std::function<saltus::Vec<S::nu>(double)>&, const std::vector<double>&, const std::vector<double>&); \
  prefix template saltus::RemainderFit saltus::piece_remainder<S>(                                               \
      const saltus::LinearisedSystem<S>&, const saltus::SimulationOptions&, int, const saltus::Vec<2 * S::nq>&, \
      const saltus::ConewisePiece<S>&, double, const std::vector<double>&);                                    \
  prefix template class saltus::GainSchedule<S>;                                                                 \
  prefix template saltus::LqrDesign<S> saltus::lqr_design<S>(const saltus::LinearisedSystem<S>&,                 \
                                                             const saltus::LqrWeights<S>&, const saltus::LqrOptions&); \
  prefix template class saltus::ReferenceSpreadingController<S>;                                                 \
  prefix template class saltus::ClosedLoopLinearisation<S>;                                                      \
  prefix template saltus::StabilityReport saltus::check_stability<S>(const saltus::ClosedLoopLinearisation<S>&,  \
                                                                     const saltus::StabilityOptions<S>&, double); \
  prefix template saltus::PeriodicStabilityReport saltus::check_periodic_stability<S>(                           \
      const saltus::ClosedLoopLinearisation<S>&, double, const saltus::StabilityOptions<S>&, double);            \
  prefix template saltus::MonteCarloReport saltus::monte_carlo<S>(                                               \
      const S&, const saltus::SimulationOptions&, const saltus::ReferenceSpreadingController<S>&,                \
      const saltus::ClosedLoopLinearisation<S>&, const saltus::MonteCarloOptions<S>&);                         \
  prefix template saltus::ReferenceAnalysis<S> saltus::analyse_reference<S>(                                     \
      const S&, const saltus::HybridTrajectory<S>&, const saltus::SimulationOptions&,                            \
      const saltus::ReferenceAnalysisOptions<S>&);

/// In the scene's header, after SALTUS_DECLARE_SCENE: its sensitivity machinery is compiled elsewhere.
#define SALTUS_DECLARE_SCENE_SENSITIVITY(S) SALTUS_SENSITIVITY_TEMPLATES(extern, S)
