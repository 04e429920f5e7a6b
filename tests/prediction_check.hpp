// The validation protocol's item 4 (DESIGN.md): the first-order prediction of a perturbed motion
// against the nonlinear re-simulation of the perturbed system. For eps in `eps_values`, the
// Simulator runs from x(t0) + eps z0 under u + eps v(t) to each sample time t; with k the number
// of jumps the perturbed run has seen, the remainder
//     r(eps) = max_t |x_eps(t) - x_k(t) - eps z_k(t)|_inf
// (x_k: extended segment k of reference spreading, integrated afresh to t at the simulation's
// tolerances; z_k: LinearisedSystem's prediction on that segment) must shrink like eps^2.
#pragma once

#include "references.hpp"

#include <cmath>
#include <functional>
#include <vector>

namespace saltus::references {

struct RemainderFit {
  std::vector<double> eps, remainder;
  double slope = 0.0;  ///< least-squares slope of log r against log eps
  bool structure_matched = true;  ///< every perturbed run saw a jump count the reference has
};

inline double fitted_slope(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double lx = std::log(x[k]), ly = std::log(y[k]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

inline std::vector<double> default_eps() { return {1e-2, 1e-3, 1e-4, 1e-5, 1e-6}; }

template <Scene S>
RemainderFit remainder_fit(const Reference<S>& ref, const LinearisedSystem<S>& lin, const Vec<2 * S::nq>& z0,
                           const std::function<Vec<S::nu>(double)>& v, const std::vector<double>& sample_times,
                           const std::vector<double>& eps_values = default_eps()) {
  constexpr int nx = 2 * S::nq;
  const auto& traj = ref.trajectory;
  const auto prediction = lin.predict(z0, v);
  Simulator<S> sim(ref.scene, ref.options);
  DormandPrinceIntegrator<S> integrator(ref.options.integrator);
  const double t0 = traj.t_begin();
  const Vec<nx> x0 = lin.begin_state(0);
  // x_k(t): extended segment k integrated from its start to t (events off).
  auto extended_state = [&](int k, double t) {
    ModeSystem<S> sys(ref.scene, traj.input);
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
  fit.slope = fitted_slope(fit.eps, fit.remainder);
  return fit;
}

}  // namespace saltus::references
