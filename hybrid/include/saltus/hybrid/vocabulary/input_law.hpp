// Input laws: u = law(t, x, mode). Open loop, u(t), or feedback, u(t, x, mode), as tracking
// controllers need; a trajectory keeps its law to evaluate inputs anywhere (reference spreading).
#pragma once

#include <saltus/hybrid/vocabulary/mode.hpp>
#include <saltus/hybrid/vocabulary/scene.hpp>

#include <functional>

namespace saltus {

/// u = law(t, x, mode). The trajectory keeps it to evaluate inputs anywhere (reference spreading).
template <Scene S>
using InputLaw = std::function<VecT<double, S::nu>(double t, const VecT<double, 2 * S::nq>& x, const Mode<S::nc>& mode)>;

/// u = law(segment, t, x, mode): a law that also knows how many events the motion has seen, the
/// index of the segment it is in (0 before the first event, k after the k-th). Reference-spreading
/// tracking controllers need it: after its k-th event the plant is compared with the reference's
/// segment k, whatever the time (sensitivity/tracking.hpp). The simulator advances the index at
/// the plant's own events (Simulator::run with a segmented law): while an event is resolved
/// (post-event mode selection, chained transitions) the law already sees the new index.
template <Scene S>
using SegmentedInputLaw = std::function<VecT<double, S::nu>(int segment, double t, const VecT<double, 2 * S::nq>& x,
                                                             const Mode<S::nc>& mode)>;

/// u = f(t), independent of the state.
template <Scene S, class F>
InputLaw<S> open_loop(F f) {
  return [f](double t, const VecT<double, 2 * S::nq>&, const Mode<S::nc>&) { return VecT<double, S::nu>(f(t)); };
}

/// u = 0 (also the law of scenes without inputs).
template <Scene S>
InputLaw<S> zero_input() {
  return [](double, const VecT<double, 2 * S::nq>&, const Mode<S::nc>&) { return VecT<double, S::nu>::Zero().eval(); };
}

}  // namespace saltus
