// A hybrid trajectory: smooth segments (a mode, a time interval, the dense output of x and the
// input law that drove it) separated by events (the time, the guards that fired, x- and x+, the
// modes before and after, and every transition of a chain at that instant). Segment i ends at
// event i; segment i + 1 starts there. Writing them (CSV, JSON) and reading a reference back:
// trajectory_io.hpp.
#pragma once

#include <saltus/hybrid/vocabulary/contact_force.hpp>
#include <saltus/hybrid/vocabulary/dense_output.hpp>
#include <saltus/hybrid/vocabulary/guard.hpp>
#include <saltus/hybrid/vocabulary/impact_mode.hpp>
#include <saltus/hybrid/vocabulary/input_law.hpp>
#include <saltus/hybrid/vocabulary/mode.hpp>
#include <saltus/hybrid/vocabulary/zeno_completion.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace saltus {

template <Scene S>
struct Segment {
  Mode<S::nc> mode;
  double t_begin = 0.0, t_end = 0.0;
  DenseOutput<2 * S::nq> x;
  /// A contact sliding on the surface through the segment under the equivalent control of a
  /// mode-switching input law (ModeSystem::set_sliding), -1 when none; then the open mode and the
  /// force floor of the equivalent control, which HybridTrajectory::input applies on the segment.
  int sliding_contact = -1;
  Mode<S::nc> sliding_open_mode{};
  double sliding_force_floor = 0.0;
};

/// One transition of the (possibly chained) mode changes at an event instant.
template <Scene S>
struct Transition {
  std::vector<Guard> guards;  ///< the guards that triggered it (empty: initial impact)
  Mode<S::nc> mode_before, mode_after;
  VecT<double, 2 * S::nq> x_before, x_after;
  bool impact = false;           ///< an impulse was applied (x_after != x_before in v)
  ImpactMode<S::nc> impulse_mode;  ///< who took an impulse, how
  std::array<ContactForce<double>, S::nc> impulse{};
  /// Solutions of the acceleration-level mode selection of this transition (ModeSelector's
  /// SelectionUniqueness): 1 when unique or not checked, > 1 when another mode was possible
  /// (the one taken follows ModeSelectionOptions::ambiguity).
  int selection_solutions = 1;
  /// The contact the transition left sliding on the surface under the equivalent control of a
  /// mode-switching input law (TransitionResolver::select_consistent), -1 when none.
  int sliding_contact = -1;
  /// The transition is the Zeno completion of an accumulation of impacts (ZenoCompletion): the
  /// limit state projected onto the accumulating contacts, not the jump map of a guard crossing
  /// (guards empty, impact true, impulse_mode empty). Analyses that differentiate an event's jump
  /// refuse it.
  bool zeno_completion = false;
  /// The transition is an impact without collision (SimulationOptions::painleve,
  /// dynamics/impact_without_collision.hpp): the tangential impulse that resolves Painleve's
  /// inconsistent configuration of a closed sliding contact, at zero approach velocity. guards
  /// empty (a start, or a selection without solution) or the contact's release (the end of the
  /// closed branch of Painleve's indeterminacy, simulation/transition.hpp), impact true, impulse
  /// the total (P_n, P_t) of the slip and stick phases, impulse_mode Stick for that contact (the
  /// jump map of which gives the same velocity jump).
  bool impact_without_collision = false;
};

template <Scene S>
struct Event {
  double t = 0.0;
  VecT<double, 2 * S::nq> x_minus, x_plus;
  Mode<S::nc> mode_before, mode_after;
  std::vector<Transition<S>> transitions;  ///< in the order applied (a chain has several)
  /// Fired by a jump of the input at a breakpoint (SimulationOptions::breakpoints: a force guard,
  /// release or slip onset, due under the input after it), not by a guard crossing zero: its time
  /// is the breakpoint's whatever the state (a fixed-time event for the jump gains).
  bool input_jump = false;

  bool impact() const {
    for (const auto& tr : transitions)
      if (tr.impact) return true;
    return false;
  }
  std::vector<Guard> guards() const {
    std::vector<Guard> all;
    for (const auto& tr : transitions) all.insert(all.end(), tr.guards.begin(), tr.guards.end());
    return all;
  }
};

enum class SimulationStatus { Completed, Zeno, MaxEvents };

inline const char* to_string(SimulationStatus s) {
  switch (s) {
    case SimulationStatus::Completed: return "completed";
    case SimulationStatus::Zeno: return "zeno";
    case SimulationStatus::MaxEvents: return "max-events";
  }
  return "?";
}

struct SimulationStatistics {
  long steps = 0, rejected_steps = 0, rhs_evaluations = 0;
  double wall_seconds = 0.0;
  /// Mode selections (the initial one included) whose acceleration-level problem had several
  /// solutions (see Transition::selection_solutions).
  int ambiguous_selections = 0;
  /// Events after which a contact slides on the surface under the equivalent control of an input
  /// law that switches with the contact mode (Transition::sliding_contact).
  int sliding_events = 0;
  /// Impacts without collision applied to Painleve's inconsistent configuration
  /// (SimulationOptions::painleve; Transition::impact_without_collision).
  int impacts_without_collision = 0;
};

template <Scene S>
class HybridTrajectory {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu, nc = S::nc;
  using State = VecT<double, nx>;
  using Input = VecT<double, nu>;

  std::vector<Segment<S>> segments;
  std::vector<Event<S>> events;
  InputLaw<S> input;  ///< u(t, x, mode)
  /// s, sorted: the times where `input` may jump or kink in t (a piecewise-constant optimal input's
  /// element boundaries; the SimulationOptions::breakpoints a simulation ran with, those inside its
  /// interval). Whoever simulates along this reference (the Monte Carlo plant under a tracking
  /// controller, ReferenceSpreadingController::breakpoints; the conewise gains' re-resolution)
  /// stops its steps there too: an input jump that a step straddles is located as a guard crossing
  /// to the event tolerance instead of being the fixed-time event it is (Event::input_jump).
  std::vector<double> input_breakpoints;
  SimulationStatus status = SimulationStatus::Completed;
  /// s: the predicted accumulation time (status Zeno, or the last accumulation the run was
  /// continued past, see zeno_completions; NaN otherwise), extrapolated from the touchdown times
  /// (Simulator, simulator.hpp).
  double zeno_time = std::numeric_limits<double>::quiet_NaN();
  /// s: how far zeno_time may be from the accumulation time of the motion: the sum of
  /// zeno_time_extrapolation_uncertainty and zeno_time_integration_uncertainty (their derivation in
  /// simulation/accumulation_time.hpp). Measured against closed forms at relative tolerances 1e-8,
  /// 1e-10 (the default) and 1e-12 (tests/test_accumulation.cpp, AccumulationTable; the table in
  /// docs/simulation.md), with the default Dormand-Prince backend: the error is at most 0.56 of
  /// it, and at least 1/17 of it where the error is above the event location's resolution (100
  /// root tolerances of the time); where it is round-off (flights that the integrator follows
  /// exactly: a ball or a box in free fall) the statement, made from the tolerances, is far larger
  /// than the error. Infinite with the CVODE backends, whose touchdown times err by more than
  /// the integration part allows and not in proportion to their tolerances (accumulation_time.hpp):
  /// no bound is stated for their zeno_time (use Dormand-Prince where it matters). Infinite when
  /// too few touchdowns were recorded to extrapolate (zeno_time is then the geometric estimate, a
  /// guess); NaN without a Zeno status.
  double zeno_time_uncertainty = std::numeric_limits<double>::quiet_NaN();
  /// s: the extrapolation's part of zeno_time_uncertainty, how far zeno_time may be from the
  /// accumulation time of the touchdown times as located: twice the change of the extrapolation's
  /// second order over the last period (simulator.hpp); infinite with the geometric estimate.
  double zeno_time_extrapolation_uncertainty = std::numeric_limits<double>::quiet_NaN();
  /// s: the integration's part of zeno_time_uncertainty, the error that the touchdown times carry
  /// from the integration and pass into zeno_time: 4 (relative_tolerance + absolute_tolerance /
  /// state scale) times the time integrated, plus the event location's resolution carried through
  /// the extrapolation, plus the uncertainty of an accumulation time the run was continued from
  /// (simulation/accumulation_time.hpp, which derives it and says what it does not cover).
  double zeno_time_integration_uncertainty = std::numeric_limits<double>::quiet_NaN();
  /// The accumulations the run was continued past (SimulationOptions::zeno_completion), in time
  /// order; empty without one.
  std::vector<ZenoCompletion> zeno_completions;
  SimulationStatistics statistics;

  double t_begin() const { return segments.empty() ? 0.0 : segments.front().t_begin; }
  double t_end() const { return segments.empty() ? 0.0 : segments.back().t_end; }
  int segment_count() const { return static_cast<int>(segments.size()); }

  /// x on segment i at t (t within the segment's interval).
  State state(int i, double t) const {
    const auto& s = segment(i);
    SALTUS_REQUIRE(t >= s.t_begin - 1e-12 * std::max(1.0, std::abs(t)) && t <= s.t_end + 1e-12 * std::max(1.0, std::abs(t)), "t = ", t, " is outside segment ", i, " [", s.t_begin, ", ", s.t_end, "]");
    if (s.x.empty()) return i < static_cast<int>(events.size()) ? events[i].x_minus : final_state_;
    return s.x.value(t);
  }
  /// u on segment i at t.
  Input input_at(int i, double t) const { return input(t, state(i, t), segment(i).mode); }

  /// The segment containing t; at an event time, the one after the event.
  int segment_at(double t) const {
    for (int i = segment_count() - 1; i >= 0; --i)
      if (t >= segments[i].t_begin) return i;
    return 0;
  }
  State state_at(double t) const { return state(segment_at(t), std::min(t, segments[segment_at(t)].t_end)); }

  const State& final_state() const { return final_state_; }
  void set_final_state(const State& x) { final_state_ = x; }

 private:
  const Segment<S>& segment(int i) const {
    SALTUS_REQUIRE(i >= 0 && i < segment_count(), "segment index ", i, " out of range [0, ",
                  segment_count(), ")");
    return segments[i];
  }
  State final_state_ = State::Zero();
};

/// A reference produced elsewhere (another optimiser, an experiment): samples (t_k, x_k, u_k)
/// in time order and its event times. At an event the samples may repeat the time, x- first and
/// x+ second (as write_csv writes them; reading and writing: trajectory_io.hpp). Polish it with
/// polish() (simulator.hpp).
template <Scene S>
struct ImportedReference {
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu;
  using State = VecT<double, nx>;
  using Input = VecT<double, nu>;

  std::vector<double> t;
  std::vector<State> x;
  std::vector<Input> u;
  std::vector<double> event_times;
  /// Segment index of every sample (read_reference_csv fills it); if empty, segment_of counts
  /// the event times before the sample (the later samples of a repeated time are post-event).
  std::vector<int> segment;

  std::size_t size() const { return t.size(); }

  int segment_of(std::size_t k) const {
    if (segment.size() == t.size()) return segment[k];
    int s = static_cast<int>(std::lower_bound(event_times.begin(), event_times.end(), t[k]) - event_times.begin());
    const bool at_event = std::binary_search(event_times.begin(), event_times.end(), t[k]);
    if (at_event && k > 0 && t[k - 1] == t[k]) ++s;
    return s;
  }

  /// Throws InvalidArgument unless there are >= 2 samples, sizes agree, times are finite and
  /// non-decreasing, and every value is finite.
  void validate() const {
    SALTUS_REQUIRE(t.size() >= 2, "an imported reference needs at least 2 samples, got ", t.size());
    SALTUS_REQUIRE(x.size() == t.size() && u.size() == t.size(), "imported reference: ", t.size(),
                  " times but ", x.size(), " states and ", u.size(), " inputs");
    for (std::size_t k = 0; k < t.size(); ++k) {
      SALTUS_REQUIRE(std::isfinite(t[k]) && x[k].allFinite() && u[k].allFinite(), 
                    "imported reference: sample ", k, " (t = ", t[k], ") is not finite");
      SALTUS_REQUIRE(k == 0 || t[k] >= t[k - 1], "imported reference: times decrease at sample ", k,
                    " (", t[k - 1], " then ", t[k], ")");
    }
    SALTUS_REQUIRE(t.back() > t.front(), "imported reference spans no time");
  }

  /// u(t): linear between consecutive samples, right-continuous where a time repeats (an input
  /// that jumps at an event takes its post-event value there), held constant outside.
  Input input(double time) const {
    if (time <= t.front()) return u.front();
    if (time >= t.back()) return u.back();
    const std::size_t k = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), time) - t.begin()) - 1;
    const double span = t[k + 1] - t[k];
    if (!(span > 0)) return u[k];
    const double s = (time - t[k]) / span;
    return ((1.0 - s) * u[k] + s * u[k + 1]).eval();
  }
};

}  // namespace saltus
