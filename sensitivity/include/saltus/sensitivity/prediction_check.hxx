// Definitions of prediction_check.hpp.
#pragma once

#include <saltus/hybrid/simulation/integrator_dopri.hpp>
#include <saltus/hybrid/simulation/simulator.hpp>
#include <saltus/sensitivity/prediction_check.hpp>

#include <algorithm>

namespace saltus {

template <Scene S>
RemainderFit prediction_remainder(const LinearisedSystem<S>& lin, const SimulationOptions& options,
                                  const Vec<2 * S::nq>& z0, const std::function<Vec<S::nu>(double)>& v,
                                  const std::vector<double>& sample_times, const std::vector<double>& eps_values) {
  constexpr int nx = 2 * S::nq;
  const S& scene = lin.scene();
  const auto& traj = lin.reference().reference();
  const auto prediction = lin.predict(z0, v);
  Simulator<S> sim(scene, options);
  DormandPrinceIntegrator<S> integrator(options.integrator);
  const double t0 = traj.t_begin();
  const Vec<nx> x0 = lin.begin_state(0);
  // x_k(t): extended segment k integrated from its start to t (events off).
  auto extended_state = [&](int k, double t) {
    ModeSystem<S> sys(scene, traj.input);
    sys.set_mode(lin.mode(k));
    Vec<nx> x = lin.begin_state(k);
    integrator.integrate(sys, lin.t_begin(k), x, t, 0.0, nullptr, false);
    return x;
  };
  // Jumps a perturbed run sees per reference event: one, or one per micro-event of the conewise
  // piece the prediction's deviation falls in at a simultaneous event.
  std::vector<int> micro_events(traj.events.size(), 1);
  for (int i = 0; i < static_cast<int>(traj.events.size()); ++i) {
    if (!lin.conewise(i)) continue;
    const double te = lin.t_end(i);
    micro_events[i] = static_cast<int>(lin.conewise_gain(i).piece(prediction.z_end(i), v(te)).order.size());
  }
  RemainderFit fit;
  for (double eps : eps_values) {
    const InputLaw<S> law = traj.input;
    const InputLaw<S> perturbed = [law, v, eps](double t, const Vec<nx>& x, const Mode<S::nc>& m) {
      return Vec<S::nu>(law(t, x, m) + eps * v(t));
    };
    double r = 0.0;
    for (double t : sample_times) {
      const auto run = sim.run(Vec<nx>(x0 + eps * z0), traj.segments.front().mode, t0, t, perturbed);
      // k: the reference events whose micro-events the run has all seen.
      int k = 0, seen = 0;
      const int jumps = static_cast<int>(run.events.size());
      while (k < static_cast<int>(micro_events.size()) && seen + micro_events[k] <= jumps) seen += micro_events[k++];
      if (seen != jumps || k >= traj.segment_count() || !(run.segments.back().mode == traj.segments[k].mode)) {
        fit.structure_matched = false;
        continue;
      }
      const Vec<nx> d = run.final_state() - extended_state(k, t) - eps * prediction.z(k, t);
      r = std::max(r, d.cwiseAbs().maxCoeff());
    }
    fit.eps.push_back(eps);
    fit.remainder.push_back(std::max(r, 1e-300));
  }
  fit.slope = fitted_log_slope(fit.eps, fit.remainder);
  return fit;
}

template <Scene S>
RemainderFit piece_remainder(const LinearisedSystem<S>& lin, const SimulationOptions& options, int event,
                             const Vec<2 * S::nq>& z0, const ConewisePiece<S>& piece, double t,
                             const std::vector<double>& eps_values) {
  constexpr int nx = 2 * S::nq, nu = S::nu;
  const S& scene = lin.scene();
  const auto& traj = lin.reference().reference();
  SALTUS_REQUIRE(event >= 0 && event < static_cast<int>(traj.events.size()) && lin.conewise(event),
                 "piece_remainder: event ", event, " is not a simultaneous event of the reference");
  const double t_event = lin.t_end(event);
  SALTUS_REQUIRE(t > t_event, "piece_remainder: t = ", t, " is not after the event at ", t_event);
  const auto zero = [](double) { return Vec<nu>::Zero().eval(); };
  // z- at the event: propagated through the events before it (v = 0).
  Vec<nx> z = z0;
  std::size_t expected_events = piece.order.size();
  for (int k = 0; k < event; ++k) {
    z = lin.propagate(k, z, zero, lin.t_end(k));
    ++expected_events;
    if (lin.conewise(k)) {
      const ConewisePiece<S>& before = lin.conewise_gain(k).piece(z, Vec<nu>::Zero());
      expected_events += before.order.size() - 1;
      if (!before.nominal_outcome)
        throw SimultaneousActivation(detail::concat("piece_remainder: at the earlier simultaneous event ", k,
                                                    " the perturbation's cone does not end in the nominal outcome"));
      z = (before.G_z * z).eval();
    } else {
      z = (lin.gains()[k].G_z * z).eval();
    }
  }
  const Vec<nx> z_minus = lin.propagate(event, z, zero, t_event);
  const Vec<nx> z_plus = piece.G_z * z_minus;
  DormandPrinceIntegrator<S> integrator(options.integrator);
  const auto flow = [&](Vec<nx> x) {
    ModeSystem<S> sys(scene, traj.input);
    sys.set_mode(piece.mode_after);
    integrator.integrate(sys, t_event, x, t, 0.0, nullptr, false);
    return x;
  };
  const Vec<nx> x_piece = flow(piece.x_plus);
  Vec<nx> z_t = Vec<nx>::Zero();
  if (z_plus.norm() > 0) {
    const double h = 1e-6 / z_plus.norm();
    z_t = (flow(Vec<nx>(piece.x_plus + h * z_plus)) - flow(Vec<nx>(piece.x_plus - h * z_plus))) / (2 * h);
  }
  Simulator<S> sim(scene, options);
  RemainderFit fit;
  for (const double eps : eps_values) {
    const auto run = sim.run(Vec<nx>(lin.begin_state(0) + eps * z0), traj.segments.front().mode, traj.t_begin(), t,
                             traj.input);
    // The same contact modes (open / stick / slip, and the sign of a planar slip); a spatial
    // slip's stored direction is the sliding direction at the slip's start, which moves with eps.
    bool same_modes = true;
    for (int i = 0; i < S::nc; ++i) {
      const ContactState &a = run.segments.back().mode[i], &b = piece.mode_after[i];
      same_modes = same_modes && a.mode == b.mode &&
                   (a.mode != ContactMode::Slip || scene.contact(i).tangents() != 1 || a.slip_direction == b.slip_direction);
    }
    fit.structure_matched = fit.structure_matched && run.events.size() == expected_events && same_modes;
    fit.eps.push_back(eps);
    fit.remainder.push_back(std::max((run.final_state() - x_piece - eps * z_t).cwiseAbs().maxCoeff(), 1e-300));
  }
  fit.slope = fitted_log_slope(fit.eps, fit.remainder);
  return fit;
}

}  // namespace saltus
