// Compile a scene's machinery once (Pinocchio's pattern): every algorithm of saltus::hybrid that
// is templated on the scene is declared in its .hpp and defined in the .hxx beside it. A program
// that includes only the .hpp files does not compile those algorithms; it links them from the
// one translation unit that instantiates them for its scene:
//
//   // my_scene.hpp: the scene, then
//   #include <saltus/hybrid/instantiate.hpp>
//   struct MyScene { ... };
//   SALTUS_DECLARE_SCENE(MyScene)        // at namespace scope: "compiled elsewhere"
//
//   // my_scene.cpp: compiled once, linked with every program that uses MyScene
//   #include "my_scene.hpp"
//   #include <saltus/hybrid/instantiate.hxx>
//   SALTUS_INSTANTIATE_SCENE(MyScene)
//
// The scene type must be named with its namespace (or from the global namespace). A scene whose
// instantiation is large can spread it over several .cpp files with the stage macros
// SALTUS_INSTANTIATE_SCENE_DYNAMICS / _DERIVATIVES / _SIMULATION (each in one file, all three
// once). Without any of this, including <saltus/hybrid/header_only.hpp> compiles everything in
// the including translation unit (the header-only path).
//
// What is compiled per scene: the kernels of one state for T = double and for the dual number of
// the derivatives (StateInputDual<S>: evaluate_contact, evaluate_dynamics, evaluate_kinematics,
// evaluate_flow, apply_jump_map), ImpactSolver, ModeSelector, ConstraintProjection,
// flow_jacobian, guard_gradient, jump_map_jacobian, ModeSystem, both integrators (CVODE's where
// SALTUS_WITH_CVODE is defined: the component saltus::cvode),
// TransitionResolver, Simulator, ExtendedReference and polish. The scene-free contact numerics
// are compiled once in the library.
#pragma once

#include <saltus/hybrid/dynamics/constraints.hpp>
#include <saltus/hybrid/dynamics/derivatives.hpp>
#include <saltus/hybrid/dynamics/flow.hpp>
#include <saltus/hybrid/dynamics/impact.hpp>
#include <saltus/hybrid/dynamics/jump_map.hpp>
#include <saltus/hybrid/dynamics/kinematics.hpp>
#include <saltus/hybrid/dynamics/mode_selection.hpp>
#include <saltus/hybrid/reference/reference_spreading.hpp>
#include <saltus/hybrid/reference/resimulation.hpp>
#include <saltus/hybrid/simulation/simulator.hpp>

// CVODE (BDF and Adams) is the optional component saltus::cvode: linking that target defines
// SALTUS_WITH_CVODE=1, and only then is CvodeIntegrator<S> compiled into a scene's machinery
// (without it, asking the simulator for CVODE throws InvalidArgument saying so).
#if defined(SALTUS_WITH_CVODE) && SALTUS_WITH_CVODE
#define SALTUS_DETAIL_CVODE_TEMPLATES(prefix, S) prefix template class saltus::CvodeIntegrator<S>;
#else
#define SALTUS_DETAIL_CVODE_TEMPLATES(prefix, S)
#endif

/// The kernels of one state for scalar T (double, or saltus::StateInputDual<S>).
#define SALTUS_HYBRID_KERNEL_TEMPLATES(prefix, S, T)                                                             \
  prefix template void saltus::evaluate_contact<S, T>(const S&, int, const saltus::VecT<T, S::nq>&,              \
                                                      const saltus::VecT<T, S::nq>&, saltus::ContactKinematics<S, T>&); \
  prefix template void saltus::evaluate_dynamics<S, T>(const S&, const saltus::VecT<T, S::nq>&,                  \
                                                       const saltus::VecT<T, S::nq>&, saltus::Kinematics<S, T>&); \
  prefix template void saltus::evaluate_kinematics<S, T>(const S&, const saltus::VecT<T, S::nq>&,                \
                                                         const saltus::VecT<T, S::nq>&, saltus::Kinematics<S, T>&); \
  prefix template void saltus::evaluate_flow<S, T>(const S&, const saltus::Mode<S::nc>&,                          \
                                                   const saltus::VecT<T, 2 * S::nq>&, const saltus::VecT<T, S::nu>&, \
                                                   saltus::FlowWorkspace<S, T>&);                                 \
  prefix template void saltus::apply_jump_map<S, T>(const S&, const saltus::ImpactMode<S::nc>&,                   \
                                                    const saltus::VecT<T, 2 * S::nq>&, saltus::JumpWorkspace<S, T>&, \
                                                    saltus::VecT<T, 2 * S::nq>&);

#define SALTUS_HYBRID_DYNAMICS_TEMPLATES(prefix, S) \
  SALTUS_HYBRID_KERNEL_TEMPLATES(prefix, S, double) \
  prefix template class saltus::ImpactSolver<S>;    \
  prefix template class saltus::ModeSelector<S>;    \
  prefix template class saltus::ConstraintProjection<S>;

#define SALTUS_HYBRID_DERIVATIVE_TEMPLATES(prefix, S)                                                            \
  SALTUS_HYBRID_KERNEL_TEMPLATES(prefix, S, saltus::StateInputDual<S>)                                           \
  prefix template void saltus::flow_jacobian<S>(                                                                 \
      const S&, const saltus::Mode<S::nc>&, const saltus::VecT<double, 2 * S::nq>&, const saltus::VecT<double, S::nu>&, \
      saltus::DerivativeWorkspace<S>&, saltus::VecT<double, 2 * S::nq>&, saltus::MatT<double, 2 * S::nq, 2 * S::nq>&, \
      saltus::MatT<double, 2 * S::nq, S::nu>&);                                                                  \
  prefix template double saltus::guard_gradient<S>(                                                              \
      const S&, const saltus::Mode<S::nc>&, const saltus::Guard&, const saltus::VecT<double, 2 * S::nq>&,        \
      const saltus::VecT<double, S::nu>&, saltus::DerivativeWorkspace<S>&, Eigen::Matrix<double, 1, 2 * S::nq>&, \
      Eigen::Matrix<double, 1, S::nu>&);                                                                         \
  prefix template void saltus::jump_map_jacobian<S>(const S&, const saltus::ImpactMode<S::nc>&,                  \
                                                    const saltus::VecT<double, 2 * S::nq>&,                      \
                                                    saltus::DerivativeWorkspace<S>&, saltus::VecT<double, 2 * S::nq>&, \
                                                    saltus::MatT<double, 2 * S::nq, 2 * S::nq>&);

#define SALTUS_HYBRID_SIMULATION_TEMPLATES(prefix, S)                                                  \
  prefix template class saltus::ModeSystem<S>;                                                         \
  prefix template class saltus::DormandPrinceIntegrator<S>;                                            \
  SALTUS_DETAIL_CVODE_TEMPLATES(prefix, S)                                                             \
  prefix template class saltus::TransitionResolver<S>;                                                 \
  prefix template class saltus::Simulator<S>;                                                          \
  prefix template class saltus::ExtendedReference<S>;                                                  \
  prefix template saltus::PolishResult<S> saltus::polish<S>(const S&, const saltus::ImportedReference<S>&, \
                                                            saltus::SimulationOptions, bool);

/// In the scene's header, after the scene: its machinery is compiled in one .cpp elsewhere.
#define SALTUS_DECLARE_SCENE(S)                \
  SALTUS_HYBRID_DYNAMICS_TEMPLATES(extern, S)  \
  SALTUS_HYBRID_DERIVATIVE_TEMPLATES(extern, S) \
  SALTUS_HYBRID_SIMULATION_TEMPLATES(extern, S)
