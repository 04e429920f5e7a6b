// Event-driven simulation of a scene: integrate the flow of the current mode, stop at the first
// guard crossing (all four kinds, state-input guards included), resolve the event with the event
// physics of transition.hpp (impacts, releases, slip onsets, stops, and the chain of transitions
// at the same instant), continue. The backend is options.integrator.kind: Dormand-Prince
// (integrator_dopri.hpp, the default) or CVODE BDF/Adams (integrator_cvode.hpp). Guards crossing
// within `simultaneity` of each other form one simultaneous event, resolved jointly (one impact
// problem for all touchdowns).
//
// Zeno. Accumulating impacts (a bouncing ball with e_n > 0) end the run with status Zeno and the
// predicted accumulation time, detected when one contact's flight times shrink geometrically
// over `zeno_bounces` consecutive touchdowns: with ratio r the remaining bounces last
// delta_last r / (1 - r). With `rest_velocity` > 0, an impact slower than it is taken as
// inelastic (e_n = 0): the contact comes to rest and the motion continues in contact.
//
// Definitions in simulator.hxx, compiled once per scene (saltus/hybrid/instantiate.hpp): a
// program that includes this header and links the scene's instantiation does not compile the
// simulator again.
#pragma once

#include <saltus/hybrid/simulation/integrator_cvode.hpp>
#include <saltus/hybrid/simulation/integrator_dopri.hpp>
#include <saltus/hybrid/simulation/simulation_options.hpp>
#include <saltus/hybrid/simulation/transition.hpp>
#include <saltus/hybrid/vocabulary/trajectory.hpp>

#include <memory>
#include <optional>
#include <vector>

namespace saltus {

template <Scene S>
class Simulator {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu, nc = S::nc, ng = 2 * S::nc + 1;
  using State = VecT<double, nx>;
  using Input = VecT<double, nu>;

  /// The scene must outlive the simulator. @throws InvalidArgument on a bad contact
  /// specification or non-positive tolerances.
  explicit Simulator(const S& scene, SimulationOptions options = {});
  Simulator(S&&, SimulationOptions = {}) = delete;  // would dangle
  ~Simulator();

  const SimulationOptions& options() const { return options_; }

  /// Simulates from x0 (nx = 2 nq: q then v) at t0 to t_final under `input`; the initial mode is
  /// chosen from the state (an initial impact is applied if a touching contact approaches).
  /// @throws InvalidArgument on a non-finite x0, an empty input law, t_final <= t0 or a state
  /// that penetrates a contact; NumericalFailure, ContactProblemFailure, NonSpdMassMatrix from
  /// the integration and the event physics.
  HybridTrajectory<S> run(const State& x0, double t0, double t_final, const InputLaw<S>& input);
  /// Same, from a given initial mode.
  HybridTrajectory<S> run(const State& x0, const Mode<nc>& mode0, double t0, double t_final,
                          const InputLaw<S>& input);

 private:
  HybridTrajectory<S> run_impl(const State& x0, std::optional<Mode<nc>> mode0, double t0, double t_final,
                               const InputLaw<S>& input);
  /// Records a touchdown of contact i that bounced; true when a Zeno accumulation is detected.
  bool record_touchdown(int i, double t, HybridTrajectory<S>& traj);

  const S& scene_;
  SimulationOptions options_;
  TransitionResolver<S> transitions_;
  DormandPrinceIntegrator<S> dopri_;
  std::unique_ptr<CvodeIntegrator<S>> cvode_;  ///< null with Dormand-Prince
  std::array<std::vector<double>, nc> touchdown_times_;
};

}  // namespace saltus
