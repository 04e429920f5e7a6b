// Definitions of simulator.hpp (see there for the method).
#pragma once

#include <chrono>
#include <cmath>
#include <saltus/hybrid/simulation/simulator.hpp>

namespace saltus {

template <Scene S>
Simulator<S>::Simulator(const S& scene, SimulationOptions options)
    : scene_(scene), options_(std::move(options)), transitions_(scene, options_), dopri_(options_.integrator) {
  validate_scene(scene);
  SALTUS_REQUIRE(options_.integrator.relative_tolerance > 0 && options_.integrator.absolute_tolerance > 0, "integrator tolerances must be > 0");
  // The backend: Dormand-Prince (member, always there) or CVODE (BDF/Adams), created once here.
  if (options_.integrator.kind != IntegratorKind::DormandPrince)
    cvode_ = std::make_unique<CvodeIntegrator<S>>(options_.integrator);
}

template <Scene S>
Simulator<S>::~Simulator() = default;

template <Scene S>
HybridTrajectory<S> Simulator<S>::run(const State& x0, double t0, double t_final, const InputLaw<S>& input) {
  return run_impl(x0, std::nullopt, t0, t_final, input);
}

template <Scene S>
HybridTrajectory<S> Simulator<S>::run(const State& x0, const Mode<nc>& mode0, double t0, double t_final,
                                      const InputLaw<S>& input) {
  return run_impl(x0, mode0, t0, t_final, input);
}

template <Scene S>
HybridTrajectory<S> Simulator<S>::run_impl(const State& x0, std::optional<Mode<nc>> mode0, double t0, double t_final,
                                           const InputLaw<S>& input) {
  const auto wall_start = std::chrono::steady_clock::now();
  require_finite(x0, "initial state x0");
  SALTUS_REQUIRE(std::isfinite(t0) && std::isfinite(t_final) && t_final > t0, 
                "simulation interval must be finite with t_final > t0, got [", t0, ", ", t_final, "]");
  SALTUS_REQUIRE(static_cast<bool>(input), "the input law is empty");
  HybridTrajectory<S> traj;
  traj.input = input;
  ModeSystem<S> sys(scene_, input);
  touchdown_times_.fill({});

  double t = t0;
  State x = x0;
  Mode<nc> mode;
  if (mode0) {
    mode = *mode0;
  } else {
    auto start = transitions_.start(sys, t, x);
    mode = start.mode;
    if (start.impact) {
      x = start.impact->x_plus;
      traj.events.push_back(std::move(*start.impact));
      traj.segments.push_back(Segment<S>{traj.events.back().mode_before, t, t, {}});
    }
  }

  SimulationStatistics& stats = traj.statistics;
  while (true) {
    sys.set_mode(mode);
    Segment<S> seg;
    seg.mode = mode;
    seg.t_begin = t;
    const long rhs_before = sys.rhs_evaluations();
    SegmentEndOf<S> end;
    while (true) {
      // Integrate up to the next breakpoint of the input, or t_final.
      double t_stop = t_final;
      for (double b : options_.breakpoints)
        if (b > t * (1 + 1e-15) + 1e-300 && b < t_stop) t_stop = b;
      DenseOutput<nx>* dense = options_.record_dense_output ? &seg.x : nullptr;
      end = cvode_ ? cvode_->integrate(sys, t, x, t_stop, options_.simultaneity, dense)
                   : dopri_.integrate(sys, t, x, t_stop, options_.simultaneity, dense);
      stats.steps += end.steps;
      stats.rejected_steps += end.rejected_steps;
      t = end.t;
      if (end.at_guard || t_stop == t_final) break;
    }
    stats.rhs_evaluations += sys.rhs_evaluations() - rhs_before;
    seg.t_end = end.t;
    traj.segments.push_back(std::move(seg));
    if (!end.at_guard) break;

    std::vector<Guard> fired;
    for (int k = 0; k < sys.guards().count; ++k)
      if (end.fired[k]) fired.push_back(sys.guards()[k]);
    Event<S> ev = transitions_.resolve(sys, t, x, mode, fired);
    x = ev.x_plus;
    mode = ev.mode_after;
    // Zeno bookkeeping on touchdowns that bounced (the contact is open again afterwards).
    bool zeno = false;
    for (const Guard& g : ev.guards())
      if (g.kind == GuardKind::Touchdown && !mode[g.contact].closed())
        zeno = zeno || record_touchdown(g.contact, t, traj);
    traj.events.push_back(std::move(ev));
    if (zeno) {
      traj.status = SimulationStatus::Zeno;
      break;
    }
    if (static_cast<int>(traj.events.size()) >= options_.max_events) {
      traj.status = SimulationStatus::MaxEvents;
      break;
    }
  }
  traj.set_final_state(x);
  stats.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return traj;
}

template <Scene S>
bool Simulator<S>::record_touchdown(int i, double t, HybridTrajectory<S>& traj) {
  auto& times = touchdown_times_[i];
  times.push_back(t);
  const int n = options_.zeno_bounces;
  if (static_cast<int>(times.size()) < n + 2) return false;
  // Flight times between the last n + 2 touchdowns, and their ratios.
  const std::size_t m = times.size();
  double r_min = 1.0, r_max = 0.0, last_flight = 0.0;
  for (int k = 0; k < n; ++k) {
    const double f1 = times[m - 1 - k] - times[m - 2 - k];
    const double f0 = times[m - 2 - k] - times[m - 3 - k];
    if (!(f0 > 0 && f1 > 0)) return false;
    const double r = f1 / f0;
    r_min = std::min(r_min, r);
    r_max = std::max(r_max, r);
    if (k == 0) last_flight = f1;
  }
  if (!(r_max < 1.0 && r_max - r_min < 0.05)) return false;
  const double ratio = 0.5 * (r_min + r_max);
  traj.zeno_time = t + last_flight * ratio / (1.0 - ratio);
  return true;
}

}  // namespace saltus
