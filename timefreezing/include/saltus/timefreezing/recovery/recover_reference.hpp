// The samples of a discrete time-freezing solution in physical time (time-freezing Theorem 5), as
// an ImportedReference for the event-driven re-simulation (hybrid/reference/resimulation.hpp).
#pragma once

#include <saltus/hybrid/reference/resimulation.hpp>
#include <saltus/timefreezing/recovery/discrete_events.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace saltus::timefreezing {


/// Recovers the physical-time reference from a discrete time-freezing solution (time-freezing
/// Theorem 5): the samples are the element boundaries at their physical times t (the clock
/// state; interior Radau stages are left out: with a_12 < 0 their clocks need not increase); a
/// run of frozen elements (detail::element_frozen) is removed and becomes an
/// event: the sample at its start (x-) and at its end (x+) share the event's time, x- first, and
/// the time is listed in event_times. When the run's clock advanced (its last element went on
/// past the end of the impact: FrozenPhase::clock_advance > frozen_tolerance * h), the end
/// sample is NOT the post-impact state at the event time: it keeps its own clock time, after
/// the event, and the event has no x+ sample (ImportedReference allows that). Stamping it with
/// the event time instead put a position jump into the reference (the point-mass OCP of
/// scenes/time_freezing_examples.hpp: the end sample 0.053 s of sliding, 0.087 m, after the
/// impact) and its re-simulation 0.09 away. Inputs are the applied inputs at the samples; at every
/// control-interval boundary the sample is repeated with the next interval's input, so the
/// right-continuous interpolation of ImportedReference::input reproduces the piecewise-constant
/// control exactly. Polish the result (hybrid/reference/resimulation.hpp: polish) to re-simulate
/// it with the event-driven simulator and to obtain the HybridTrajectory that the sensitivity
/// analysis takes. Throws InvalidArgument if points has no stage point, stages is not 1, 2 or 3, or
/// a point's recorded stage (FesdPoint::stage) does not match its position for that n_s.
template <Scene S, int ny, int nsw, int nu>
ImportedReference<S> recover_reference(const std::vector<FesdPoint<ny, nsw, nu>>& points, int stages,
                                       double frozen_tolerance = 1e-7) {
  constexpr int nx = 2 * S::nq;
  SALTUS_REQUIRE(stages >= 1 && points.size() >= 1 + static_cast<std::size_t>(stages) &&
                     (points.size() - 1) % static_cast<std::size_t>(stages) == 0,
                 "recover_reference: expected the initial point and n_s points per element, got ", points.size(),
                 " points for n_s = ", stages);
  SALTUS_REQUIRE(stages <= 3, "recover_reference: n_s must be 1, 2 or 3 (Radau IIA), got ", stages);
  // The points record their stage: a wrong n_s would pair stages of different elements.
  for (std::size_t k = 1; k < points.size(); ++k)
    SALTUS_REQUIRE(points[k].stage == static_cast<int>((k - 1) % static_cast<std::size_t>(stages)),
                   "recover_reference: point ", k, " is stage ", points[k].stage, " of its element, but n_s = ", stages,
                   " makes it stage ", (k - 1) % static_cast<std::size_t>(stages));
  ImportedReference<S> ref;
  // Every sample's segment is written out: a frozen run that starts on a control-interval
  // boundary has two pre-event samples at the event time (x- and its repeat with the next
  // interval's input), which ImportedReference::segment_of would otherwise count as x- and x+.
  int segment = 0;
  auto add = [&](const FesdPoint<ny, nsw, nu>& p) {
    ref.t.push_back(p.y[nx]);
    ref.x.push_back(p.y.template head<nx>());
    ref.u.push_back(p.u);
    ref.segment.push_back(segment);
  };
  const int elements = static_cast<int>((points.size() - 1) / stages);
  auto end_of = [&](int e) -> const FesdPoint<ny, nsw, nu>& { return points[static_cast<std::size_t>((e + 1) * stages)]; };
  auto frozen = [&](int e) { return detail::element_frozen(points, stages, e, frozen_tolerance); };
  add(points[0]);
  for (int e = 0; e < elements;) {
    if (frozen(e)) {
      int f = e;
      while (f + 1 < elements && frozen(f + 1)) ++f;
      // x- is the last sample (the start of the run); x+ at the same time, unless the clock ran
      // inside the run (then the end sample stays at its own, later, time).
      ref.event_times.push_back(ref.t.back());
      FesdPoint<ny, nsw, nu> plus = end_of(f);
      const double h_last = end_of(f).tau - points[static_cast<std::size_t>(f == 0 ? 0 : f * stages)].tau;
      if (plus.y[nx] - ref.t.back() <= frozen_tolerance * h_last) plus.y[nx] = ref.t.back();
      ++segment;
      add(plus);
      e = f + 1;
    } else {
      add(end_of(e));
      ++e;
    }
    // A control-interval boundary: repeat the sample with the next interval's input.
    if (e < elements && points[static_cast<std::size_t>(1 + e * stages)].interval != end_of(e - 1).interval) {
      FesdPoint<ny, nsw, nu> next = end_of(e - 1);
      next.u = points[static_cast<std::size_t>(1 + e * stages)].u;
      add(next);
    }
  }
  return ref;
}

}  // namespace saltus::timefreezing
