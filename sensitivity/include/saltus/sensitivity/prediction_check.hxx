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
  RemainderFit fit;
  for (double eps : eps_values) {
    const InputLaw<S> law = traj.input;
    const InputLaw<S> perturbed = [law, v, eps](double t, const Vec<nx>& x, const Mode<S::nc>& m) {
      return Vec<S::nu>(law(t, x, m) + eps * v(t));
    };
    double r = 0.0;
    for (double t : sample_times) {
      const auto run = sim.run(Vec<nx>(x0 + eps * z0), traj.segments.front().mode, t0, t, perturbed);
      const int k = static_cast<int>(run.events.size());
      if (k >= traj.segment_count() || !(run.segments.back().mode == traj.segments[k].mode)) {
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

}  // namespace saltus
