// Reading and writing trajectories (the data types are in trajectory.hpp): samples of t, mode,
// x and u as CSV (write_csv), read back as an ImportedReference (read_reference_csv); and the
// segments and events of a HybridTrajectory as JSON (to_json, write_json; nlohmann-json), written
// complete (TrajectoryJsonOptions::complete: the dense output and every transition) to be read back
// exactly (trajectory_from_json, read_json).
#pragma once

#include <algorithm>
#include <cmath>
#include <exception>
#include <iomanip>
#include <initializer_list>
#include <istream>
#include <limits>
#include <nlohmann/json.hpp>
#include <ostream>
#include <saltus/hybrid/vocabulary/trajectory.hpp>
#include <string>
#include <utility>
#include <vector>

namespace saltus {

/// Samples every dt (and the two sides of every event, as two rows with the same t): t,
/// segment, mode (quoted), q, v, u. A header row names the columns (t, segment, mode,
/// q0..q{nq-1}, v0..v{nq-1}, u0..u{nu-1}); numbers have 17 significant digits, so
/// read_reference_csv reads it back exactly. Each segment gives ceil((t_end - t_begin) / dt)
/// intervals (at least one) and both of its end points. dt in the trajectory's time unit (s).
/// Leaves the stream's precision at 17.
/// Calls visit(segment index, t) at the samples of write_csv: per segment ceil((t_end - t_begin) / dt)
/// equal intervals (at least one) and both of its end points, exactly.
template <Scene S, class Visit>
void for_each_sample(const HybridTrajectory<S>& traj, double dt, Visit&& visit) {
  for (int i = 0; i < traj.segment_count(); ++i) {
    const auto& s = traj.segments[i];
    const int n = std::max(1, static_cast<int>(std::ceil((s.t_end - s.t_begin) / dt)));
    // The end points exactly (t_begin + (t_end - t_begin) * n / n may round past t_end).
    for (int k = 0; k <= n; ++k) visit(i, k == n ? s.t_end : s.t_begin + (s.t_end - s.t_begin) * k / n);
  }
}

template <Scene S>
void write_csv(std::ostream& os, const HybridTrajectory<S>& traj, double dt, const S& scene) {
  constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu;
  using State = typename HybridTrajectory<S>::State;
  using Input = typename HybridTrajectory<S>::Input;
  os << std::setprecision(17) << "t,segment,mode";
  for (int k = 0; k < nq; ++k) os << ",q" << k;
  for (int k = 0; k < nq; ++k) os << ",v" << k;
  for (int k = 0; k < nu; ++k) os << ",u" << k;
  os << "\n";
  for_each_sample(traj, dt, [&](int i, double t) {
    const State x = traj.state(i, t);
    const Input u = traj.input_at(i, t);
    // The mode is quoted: a spatial slip direction is written "(dx,dy)".
    os << t << "," << i << ",\"" << describe(scene, traj.segments[i].mode) << "\"";
    for (int j = 0; j < nx; ++j) os << "," << x[j];
    for (int j = 0; j < nu; ++j) os << "," << u[j];
    os << "\n";
  });
}

/// What to_json writes.
struct TrajectoryJsonOptions {
  /// Also everything trajectory_from_json needs to rebuild the trajectory exactly (the keys marked
  /// [complete] in to_json), and non-finite numbers as the strings "inf", "-inf", "nan" instead of
  /// null. The input law is a function: it is never written.
  bool complete = false;
};

namespace detail {
/// A number as JSON: its value when finite; otherwise null, or with `exact` the string "inf",
/// "-inf" or "nan" (JSON has no non-finite numbers).
inline nlohmann::ordered_json json_number(double v, bool exact) {
  if (std::isfinite(v)) return v;
  if (!exact) return nullptr;
  return std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
}
/// A mode contact by contact: [{mode ("open", "stick", "slip"), slip_direction [dx, dy]}].
template <int NC>
nlohmann::ordered_json mode_json(const Mode<NC>& mode) {
  auto a = nlohmann::ordered_json::array();
  for (const ContactState& c : mode.contacts)
    a.push_back({{"mode", to_string(c.mode)}, {"slip_direction", {c.slip_direction[0], c.slip_direction[1]}}});
  return a;
}
template <int N>
nlohmann::ordered_json vector_json(const VecT<double, N>& x) {
  auto a = nlohmann::ordered_json::array();
  for (int j = 0; j < x.size(); ++j) a.push_back(x[j]);
  return a;
}
}  // namespace detail

/// Segments (mode, interval) and events (time, guards, x-, x+, modes) as a JSON object:
///   status           "completed", "zeno" or "max-events"
///   segments         [{mode, t_begin, t_end, steps}]: mode as describe() writes it, the
///                    interval in s, steps the pieces of its dense output; [complete] contact_modes
///                    (the mode contact by contact: [{mode, slip_direction [dx, dy]}]),
///                    sliding_contact, sliding_open_mode, sliding_force_floor (Segment's), pieces
///                    [{t0, t1, t_ref, h, degree, c}] (the dense output, PolynomialPiece: c the
///                    degree + 1 coefficient columns, each of size 2 nq)
///   events           [{t, impact, input_jump, guards: [{contact, kind}], mode_before, mode_after,
///                    x_minus, x_plus, impulses}]: input_jump true where a jump of the input at a
///                    breakpoint fired the event (Event::input_jump: its time is fixed, not a
///                    crossing), contact by its scene name, kind as to_string(GuardKind),
///                    x- and x+ of size 2 nq (q then v); impulses [{contact, normal, tangent}] of the
///                    contacts that took one, per impact of the event's chain in the order applied
///                    (N s; tangent in the contact's tangent coordinates, as many entries as it
///                    has tangents), empty without an impact; [complete] contact_modes_before,
///                    contact_modes_after, transitions [{guards [{contact (index), kind}],
///                    mode_before, mode_after (contact by contact), x_before, x_after, impact,
///                    impulse_mode [{role, slip_direction}], impulse [{normal, tangent [2]}] (every
///                    contact), selection_solutions, sliding_contact, zeno_completion,
///                    impact_without_collision (optional when read: false if absent)}]
///   zeno_time        the predicted accumulation time in s, null when not finite
///   zeno_time_uncertainty  its uncertainty in s (HybridTrajectory), null when not finite
///   zeno_time_extrapolation_uncertainty, zeno_time_integration_uncertainty  its two parts in s,
///                    null when not finite (a JSON without them reads as NaN for both)
///   zeno_completions [{t, uncertainty, last_touchdown, contacts, event}]: the accumulations the run
///                    was continued past (ZenoCompletion): times in s (uncertainty null when not
///                    finite), the accumulating contacts by scene name, the completion's event index;
///                    [complete] contact_indices
///   steps, rhs_evaluations, wall_seconds   the simulation's statistics
///   [complete] complete (true), rejected_steps, ambiguous_selections, sliding_events,
///                    impacts_without_collision (the other statistics; the last optional when read:
///                    0 if absent), input_breakpoints [s], final_state (2 nq)
/// Numbers keep their double values (a dump writes the shortest text that reads back exactly);
/// keys keep this order (nlohmann::ordered_json).
template <Scene S>
nlohmann::ordered_json to_json(const HybridTrajectory<S>& traj, const S& scene, const TrajectoryJsonOptions& options = {}) {
  constexpr int nx = 2 * S::nq;
  using detail::json_number;
  using detail::mode_json;
  const bool complete = options.complete;
  auto state = [](const typename HybridTrajectory<S>::State& x) { return detail::vector_json<nx>(x); };
  auto segments = nlohmann::ordered_json::array();
  for (const auto& s : traj.segments) {
    nlohmann::ordered_json js{
        {"mode", describe(scene, s.mode)}, {"t_begin", s.t_begin}, {"t_end", s.t_end}, {"steps", s.x.size()}};
    if (complete) {
      js["contact_modes"] = mode_json(s.mode);
      js["sliding_contact"] = s.sliding_contact;
      js["sliding_open_mode"] = mode_json(s.sliding_open_mode);
      js["sliding_force_floor"] = json_number(s.sliding_force_floor, true);
      auto pieces = nlohmann::ordered_json::array();
      for (const auto& p : s.x.pieces()) {
        auto c = nlohmann::ordered_json::array();
        for (int k = 0; k <= p.degree; ++k) c.push_back(detail::vector_json<nx>(p.c.col(k)));
        pieces.push_back(
            {{"t0", p.t0}, {"t1", p.t1}, {"t_ref", p.t_ref}, {"h", p.h}, {"degree", p.degree}, {"c", std::move(c)}});
      }
      js["pieces"] = std::move(pieces);
    }
    segments.push_back(std::move(js));
  }
  auto events = nlohmann::ordered_json::array();
  for (const auto& ev : traj.events) {
    auto guards = nlohmann::ordered_json::array();
    for (const Guard& g : ev.guards())
      guards.push_back({{"contact", scene.contact(g.contact).name}, {"kind", to_string(g.kind)}});
    auto impulses = nlohmann::ordered_json::array();
    for (const Transition<S>& tr : ev.transitions)
      for (int i = 0; i < S::nc && tr.impact; ++i) {
        if (tr.impulse_mode[i].role == ImpulseRole::None) continue;
        auto tangent = nlohmann::ordered_json::array();
        for (int k = 0; k < scene.contact(i).tangents(); ++k) tangent.push_back(tr.impulse[i].tangent[k]);
        impulses.push_back(
            {{"contact", scene.contact(i).name}, {"normal", tr.impulse[i].normal}, {"tangent", std::move(tangent)}});
      }
    nlohmann::ordered_json je{{"t", ev.t},
                              {"impact", ev.impact()},
                              {"input_jump", ev.input_jump},
                              {"guards", std::move(guards)},
                              {"mode_before", describe(scene, ev.mode_before)},
                              {"mode_after", describe(scene, ev.mode_after)},
                              {"x_minus", state(ev.x_minus)},
                              {"x_plus", state(ev.x_plus)},
                              {"impulses", std::move(impulses)}};
    if (complete) {
      je["contact_modes_before"] = mode_json(ev.mode_before);
      je["contact_modes_after"] = mode_json(ev.mode_after);
      auto transitions = nlohmann::ordered_json::array();
      for (const Transition<S>& tr : ev.transitions) {
        auto tg = nlohmann::ordered_json::array();
        for (const Guard& g : tr.guards) tg.push_back({{"contact", g.contact}, {"kind", to_string(g.kind)}});
        auto roles = nlohmann::ordered_json::array();
        auto impulse = nlohmann::ordered_json::array();
        for (int i = 0; i < S::nc; ++i) {
          const ImpulseMode& m = tr.impulse_mode[i];
          roles.push_back({{"role", to_string(m.role)}, {"slip_direction", {m.slip_direction[0], m.slip_direction[1]}}});
          impulse.push_back(
              {{"normal", tr.impulse[i].normal}, {"tangent", {tr.impulse[i].tangent[0], tr.impulse[i].tangent[1]}}});
        }
        transitions.push_back({{"guards", std::move(tg)},
                               {"mode_before", mode_json(tr.mode_before)},
                               {"mode_after", mode_json(tr.mode_after)},
                               {"x_before", state(tr.x_before)},
                               {"x_after", state(tr.x_after)},
                               {"impact", tr.impact},
                               {"impulse_mode", std::move(roles)},
                               {"impulse", std::move(impulse)},
                               {"selection_solutions", tr.selection_solutions},
                               {"sliding_contact", tr.sliding_contact},
                               {"zeno_completion", tr.zeno_completion},
                               {"impact_without_collision", tr.impact_without_collision}});
      }
      je["transitions"] = std::move(transitions);
    }
    events.push_back(std::move(je));
  }
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  j["status"] = to_string(traj.status);
  j["segments"] = std::move(segments);
  j["events"] = std::move(events);
  j["zeno_time"] = json_number(traj.zeno_time, complete);
  j["zeno_time_uncertainty"] = json_number(traj.zeno_time_uncertainty, complete);
  j["zeno_time_extrapolation_uncertainty"] = json_number(traj.zeno_time_extrapolation_uncertainty, complete);
  j["zeno_time_integration_uncertainty"] = json_number(traj.zeno_time_integration_uncertainty, complete);
  auto completions = nlohmann::ordered_json::array();
  for (const ZenoCompletion& z : traj.zeno_completions) {
    auto contacts = nlohmann::ordered_json::array();
    for (int i : z.contacts) contacts.push_back(scene.contact(i).name);
    nlohmann::ordered_json jz{{"t", z.t},
                              {"uncertainty", json_number(z.uncertainty, complete)},
                              {"last_touchdown", z.last_touchdown},
                              {"contacts", std::move(contacts)},
                              {"event", z.event}};
    if (complete) jz["contact_indices"] = z.contacts;
    completions.push_back(std::move(jz));
  }
  j["zeno_completions"] = std::move(completions);
  j["steps"] = traj.statistics.steps;
  j["rhs_evaluations"] = traj.statistics.rhs_evaluations;
  j["wall_seconds"] = traj.statistics.wall_seconds;
  if (complete) {
    j["complete"] = true;
    j["rejected_steps"] = traj.statistics.rejected_steps;
    j["ambiguous_selections"] = traj.statistics.ambiguous_selections;
    j["sliding_events"] = traj.statistics.sliding_events;
    j["impacts_without_collision"] = traj.statistics.impacts_without_collision;
    j["input_breakpoints"] = traj.input_breakpoints;
    j["final_state"] = state(traj.final_state());
  }
  return j;
}

/// to_json(traj, scene, options) on one line, then a newline. Throws nlohmann::json::type_error if
/// a contact name or mode description is not valid UTF-8.
template <Scene S>
void write_json(std::ostream& os, const HybridTrajectory<S>& traj, const S& scene,
                const TrajectoryJsonOptions& options = {}) {
  os << to_json(traj, scene, options).dump() << "\n";
}

namespace detail {
/// JSON of to_json(..., complete) read back; every failure an InvalidArgument naming the key.
struct TrajectoryJsonReader {
  static double number(const nlohmann::json& j, const std::string& what) {
    if (j.is_number()) return j.get<double>();
    if (j.is_string()) {
      const std::string s = j.get<std::string>();
      if (s == "inf") return std::numeric_limits<double>::infinity();
      if (s == "-inf") return -std::numeric_limits<double>::infinity();
      if (s == "nan") return std::numeric_limits<double>::quiet_NaN();
    }
    if (j.is_null()) return std::numeric_limits<double>::quiet_NaN();  // the summary's non-finite numbers
    throw InvalidArgument(concat("trajectory JSON: ", what, " is not a number: ", j.dump()));
  }
  static const nlohmann::json& at(const nlohmann::json& j, const char* key, const std::string& where) {
    SALTUS_REQUIRE(j.is_object() && j.contains(key), "trajectory JSON: ", where, " has no '", key, "'");
    return j.at(key);
  }
  static const nlohmann::json& array(const nlohmann::json& j, const char* key, const std::string& where) {
    const nlohmann::json& a = at(j, key, where);
    SALTUS_REQUIRE(a.is_array(), "trajectory JSON: ", where, ".", key, " is not an array");
    return a;
  }
  template <int N>
  static VecT<double, N> vector(const nlohmann::json& j, const char* key, const std::string& where) {
    return vector_of<N>(array(j, key, where), where + "." + key);
  }
  template <int N>
  static VecT<double, N> vector_of(const nlohmann::json& a, const std::string& what) {
    SALTUS_REQUIRE(a.is_array() && a.size() == static_cast<std::size_t>(N), "trajectory JSON: ", what,
                   " is not an array of ", N, " numbers");
    VecT<double, N> x;
    for (int k = 0; k < N; ++k) x[k] = number(a[static_cast<std::size_t>(k)], what);
    return x;
  }
  static int integer(const nlohmann::json& j, const char* key, const std::string& where) {
    const nlohmann::json& v = at(j, key, where);
    SALTUS_REQUIRE(v.is_number_integer(), "trajectory JSON: ", where, ".", key, " is not an integer");
    return v.get<int>();
  }
  static bool boolean(const nlohmann::json& j, const char* key, const std::string& where) {
    const nlohmann::json& v = at(j, key, where);
    SALTUS_REQUIRE(v.is_boolean(), "trajectory JSON: ", where, ".", key, " is not true or false");
    return v.get<bool>();
  }
  static std::string string(const nlohmann::json& j, const char* key, const std::string& where) {
    const nlohmann::json& v = at(j, key, where);
    SALTUS_REQUIRE(v.is_string(), "trajectory JSON: ", where, ".", key, " is not a string");
    return v.get<std::string>();
  }
  /// The one of `values` whose to_string is `name`; otherwise InvalidArgument "<what_key> '<name>'
  /// is not <expected>" (the names are those to_json writes).
  template <class E>
  static E named(const std::string& name, std::initializer_list<E> values, const std::string& what_key,
                 const char* expected) {
    for (E v : values)
      if (name == to_string(v)) return v;
    throw InvalidArgument(concat("trajectory JSON: ", what_key, " '", name, "' is not ", expected));
  }
  template <int NC>
  static Mode<NC> mode(const nlohmann::json& j, const char* key, const std::string& where) {
    const nlohmann::json& a = array(j, key, where);
    SALTUS_REQUIRE(static_cast<int>(a.size()) == NC, "trajectory JSON: ", where, ".", key, " has ", a.size(),
                   " contacts, the scene ", NC);
    Mode<NC> m;
    for (int i = 0; i < NC; ++i) {
      const std::string w = concat(where, ".", key, "[", i, "]");
      m[i].mode = named(string(a[static_cast<std::size_t>(i)], "mode", w),
                        {ContactMode::Open, ContactMode::Stick, ContactMode::Slip}, w + ".mode", "open, stick or slip");
      m[i].slip_direction = vector<2>(a[static_cast<std::size_t>(i)], "slip_direction", w);
    }
    return m;
  }
  static int contact_index(const nlohmann::json& j, const char* key, const std::string& where, int nc) {
    const int i = integer(j, key, where);
    SALTUS_REQUIRE(i >= 0 && i < nc, "trajectory JSON: ", where, ".", key, " = ", i, " is not a contact index in [0, ",
                   nc, ")");
    return i;
  }
  static GuardKind guard_kind(const std::string& s, const std::string& where) {
    return named(s, {GuardKind::Touchdown, GuardKind::Release, GuardKind::Stop, GuardKind::SlipOnset}, where + ".kind",
                 "a guard kind");
  }
  static ImpulseRole impulse_role(const std::string& s, const std::string& where) {
    return named(s, {ImpulseRole::None, ImpulseRole::Stick, ImpulseRole::Slip}, where + ".role", "an impulse role");
  }
};
}  // namespace detail

/// The trajectory that to_json(traj, scene, {.complete = true}) wrote, rebuilt exactly: every
/// segment's mode, interval and dense output (so state() evaluates bit for bit as the original),
/// every event with its transitions, the status, the Zeno fields and completions, the statistics,
/// the input breakpoints and the final state. Its input law is empty (never written): set
/// `input` before anything evaluates the input (input_at, a linearisation, analyse_reference).
/// `scene` must be the one it was written for (its contact count; the names are not checked).
/// @throws InvalidArgument naming the key: a JSON not written complete (no dense output), a
/// missing key or one of the wrong type, a mode or state of the wrong size, an unknown status,
/// mode, guard kind or impulse role, a contact index out of range, a piece of degree outside
/// [0, 5] or with the wrong coefficient count, an event count other than the segment count or one
/// fewer (an empty trajectory included).
template <Scene S>
HybridTrajectory<S> trajectory_from_json(const nlohmann::json& j, const S& scene) {
  (void)scene;
  constexpr int nx = 2 * S::nq, nc = S::nc;
  using R = detail::TrajectoryJsonReader;
  SALTUS_REQUIRE(j.is_object(), "trajectory JSON: not an object");
  SALTUS_REQUIRE(j.contains("complete") && j.at("complete") == true,
                 "trajectory JSON: not written complete (to_json with TrajectoryJsonOptions::complete, "
                 "Trajectory.to_json(complete=True) in Python): it holds no dense output to rebuild the segments from");
  HybridTrajectory<S> traj;
  traj.status = R::named(R::string(j, "status", "the trajectory"),
                         {SimulationStatus::Completed, SimulationStatus::Zeno, SimulationStatus::MaxEvents}, "status",
                         "completed, zeno or max-events");
  const nlohmann::json& segments = R::array(j, "segments", "the trajectory");
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const nlohmann::json& js = segments[i];
    const std::string w = detail::concat("segments[", i, "]");
    Segment<S> s;
    s.mode = R::mode<nc>(js, "contact_modes", w);
    s.t_begin = R::number(R::at(js, "t_begin", w), w + ".t_begin");
    s.t_end = R::number(R::at(js, "t_end", w), w + ".t_end");
    s.sliding_contact = R::integer(js, "sliding_contact", w);
    s.sliding_open_mode = R::mode<nc>(js, "sliding_open_mode", w);
    s.sliding_force_floor = R::number(R::at(js, "sliding_force_floor", w), w + ".sliding_force_floor");
    const nlohmann::json& pieces = R::array(js, "pieces", w);
    s.x.reserve(pieces.size());
    for (std::size_t k = 0; k < pieces.size(); ++k) {
      const nlohmann::json& jp = pieces[k];
      const std::string wp = detail::concat(w, ".pieces[", k, "]");
      PolynomialPiece<nx> p;
      p.t0 = R::number(R::at(jp, "t0", wp), wp + ".t0");
      p.t1 = R::number(R::at(jp, "t1", wp), wp + ".t1");
      p.t_ref = R::number(R::at(jp, "t_ref", wp), wp + ".t_ref");
      p.h = R::number(R::at(jp, "h", wp), wp + ".h");
      p.degree = R::integer(jp, "degree", wp);
      SALTUS_REQUIRE(p.degree >= 0 && p.degree <= PolynomialPiece<nx>::max_degree, "trajectory JSON: ", wp,
                     ".degree = ", p.degree, " is outside [0, ", PolynomialPiece<nx>::max_degree, "]");
      const nlohmann::json& c = R::array(jp, "c", wp);
      SALTUS_REQUIRE(static_cast<int>(c.size()) == p.degree + 1, "trajectory JSON: ", wp, ".c has ", c.size(),
                     " columns, expected degree + 1 = ", p.degree + 1);
      for (int col = 0; col <= p.degree; ++col)
        p.c.col(col) = R::vector_of<nx>(c[static_cast<std::size_t>(col)], detail::concat(wp, ".c[", col, "]"));
      s.x.append(p);
    }
    traj.segments.push_back(std::move(s));
  }
  const nlohmann::json& events = R::array(j, "events", "the trajectory");
  SALTUS_REQUIRE(events.size() + 1 == segments.size() || (events.size() == segments.size() && !segments.empty()),
                 "trajectory JSON: ", events.size(), " events for ", segments.size(),
                 " segments (as many, or one fewer, expected)");
  for (std::size_t i = 0; i < events.size(); ++i) {
    const nlohmann::json& je = events[i];
    const std::string w = detail::concat("events[", i, "]");
    Event<S> ev;
    ev.t = R::number(R::at(je, "t", w), w + ".t");
    ev.x_minus = R::vector<nx>(je, "x_minus", w);
    ev.x_plus = R::vector<nx>(je, "x_plus", w);
    ev.mode_before = R::mode<nc>(je, "contact_modes_before", w);
    ev.mode_after = R::mode<nc>(je, "contact_modes_after", w);
    ev.input_jump = R::boolean(je, "input_jump", w);
    const nlohmann::json& transitions = R::array(je, "transitions", w);
    for (std::size_t k = 0; k < transitions.size(); ++k) {
      const nlohmann::json& jt = transitions[k];
      const std::string wt = detail::concat(w, ".transitions[", k, "]");
      Transition<S> tr;
      const nlohmann::json& guards = R::array(jt, "guards", wt);
      for (std::size_t g = 0; g < guards.size(); ++g) {
        const std::string wg = detail::concat(wt, ".guards[", g, "]");
        tr.guards.push_back({R::contact_index(guards[g], "contact", wg, nc),
                             R::guard_kind(R::string(guards[g], "kind", wg), wg)});
      }
      tr.mode_before = R::mode<nc>(jt, "mode_before", wt);
      tr.mode_after = R::mode<nc>(jt, "mode_after", wt);
      tr.x_before = R::vector<nx>(jt, "x_before", wt);
      tr.x_after = R::vector<nx>(jt, "x_after", wt);
      tr.impact = R::boolean(jt, "impact", wt);
      const nlohmann::json& roles = R::array(jt, "impulse_mode", wt);
      const nlohmann::json& impulse = R::array(jt, "impulse", wt);
      SALTUS_REQUIRE(static_cast<int>(roles.size()) == nc && static_cast<int>(impulse.size()) == nc,
                     "trajectory JSON: ", wt, ".impulse_mode and .impulse must have one entry per contact (", nc, ")");
      for (int c = 0; c < nc; ++c) {
        const std::string wr = detail::concat(wt, ".impulse_mode[", c, "]"), wi = detail::concat(wt, ".impulse[", c, "]");
        const auto cc = static_cast<std::size_t>(c);
        tr.impulse_mode[c].role = R::impulse_role(R::string(roles[cc], "role", wr), wr);
        tr.impulse_mode[c].slip_direction = R::vector<2>(roles[cc], "slip_direction", wr);
        tr.impulse[c].normal = R::number(R::at(impulse[cc], "normal", wi), wi + ".normal");
        tr.impulse[c].tangent = R::vector<2>(impulse[cc], "tangent", wi);
      }
      tr.selection_solutions = R::integer(jt, "selection_solutions", wt);
      tr.sliding_contact = R::integer(jt, "sliding_contact", wt);
      tr.zeno_completion = R::boolean(jt, "zeno_completion", wt);
      tr.impact_without_collision =
          jt.contains("impact_without_collision") && R::boolean(jt, "impact_without_collision", wt);
      ev.transitions.push_back(std::move(tr));
    }
    traj.events.push_back(std::move(ev));
  }
  traj.zeno_time = R::number(R::at(j, "zeno_time", "the trajectory"), "zeno_time");
  traj.zeno_time_uncertainty = R::number(R::at(j, "zeno_time_uncertainty", "the trajectory"), "zeno_time_uncertainty");
  for (auto [key, part] : {std::pair{"zeno_time_extrapolation_uncertainty", &traj.zeno_time_extrapolation_uncertainty},
                           std::pair{"zeno_time_integration_uncertainty", &traj.zeno_time_integration_uncertainty}})
    if (j.contains(key)) *part = R::number(j.at(key), key);  // absent from the JSON of earlier versions
  const nlohmann::json& completions = R::array(j, "zeno_completions", "the trajectory");
  for (std::size_t k = 0; k < completions.size(); ++k) {
    const nlohmann::json& jz = completions[k];
    const std::string w = detail::concat("zeno_completions[", k, "]");
    ZenoCompletion z;
    z.t = R::number(R::at(jz, "t", w), w + ".t");
    z.uncertainty = R::number(R::at(jz, "uncertainty", w), w + ".uncertainty");
    z.last_touchdown = R::number(R::at(jz, "last_touchdown", w), w + ".last_touchdown");
    const nlohmann::json& contacts = R::array(jz, "contact_indices", w);
    for (std::size_t c = 0; c < contacts.size(); ++c) {
      SALTUS_REQUIRE(contacts[c].is_number_integer() && contacts[c].get<int>() >= 0 && contacts[c].get<int>() < nc,
                     "trajectory JSON: ", w, ".contact_indices[", c, "] is not a contact index in [0, ", nc, ")");
      z.contacts.push_back(contacts[c].get<int>());
    }
    z.event = R::integer(jz, "event", w);
    SALTUS_REQUIRE(z.event >= 0 && z.event < static_cast<int>(events.size()), "trajectory JSON: ", w, ".event = ",
                   z.event, " is not an event index");
    traj.zeno_completions.push_back(std::move(z));
  }
  const auto count = [&](const char* key) {
    const nlohmann::json& v = R::at(j, key, "the trajectory");
    SALTUS_REQUIRE(v.is_number_integer(), "trajectory JSON: ", key, " is not an integer");
    return v.get<long>();
  };
  traj.statistics.steps = count("steps");
  traj.statistics.rejected_steps = count("rejected_steps");
  traj.statistics.rhs_evaluations = count("rhs_evaluations");
  traj.statistics.wall_seconds = R::number(R::at(j, "wall_seconds", "the trajectory"), "wall_seconds");
  traj.statistics.ambiguous_selections = static_cast<int>(count("ambiguous_selections"));
  traj.statistics.sliding_events = static_cast<int>(count("sliding_events"));
  traj.statistics.impacts_without_collision =
      j.contains("impacts_without_collision") ? static_cast<int>(count("impacts_without_collision")) : 0;
  const nlohmann::json& breakpoints = R::array(j, "input_breakpoints", "the trajectory");
  for (std::size_t k = 0; k < breakpoints.size(); ++k)
    traj.input_breakpoints.push_back(R::number(breakpoints[k], detail::concat("input_breakpoints[", k, "]")));
  traj.set_final_state(R::vector<nx>(j, "final_state", "the trajectory"));
  return traj;
}

/// trajectory_from_json of the JSON text read from `in` (write_json's output with complete).
/// @throws InvalidArgument: text that is not JSON (with the parser's message), and as
/// trajectory_from_json.
template <Scene S>
HybridTrajectory<S> read_json(std::istream& in, const S& scene) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw InvalidArgument(std::string("trajectory JSON: ") + e.what());
  }
  return trajectory_from_json(j, scene);
}

namespace detail {
// Splits one CSV line at commas outside double quotes; quotes are removed, fields trimmed.
inline void split_csv_line(const std::string& line, std::vector<std::string>& fields) {
  fields.clear();
  std::string field;
  bool quoted = false;
  for (char ch : line) {
    if (ch == '"') {
      quoted = !quoted;
    } else if (ch == ',' && !quoted) {
      fields.push_back(field);
      field.clear();
    } else if (ch != '\r') {
      field.push_back(ch);
    }
  }
  fields.push_back(field);
  for (auto& f : fields) {
    const auto b = f.find_first_not_of(" \t"), e = f.find_last_not_of(" \t");
    f = b == std::string::npos ? std::string() : f.substr(b, e - b + 1);
  }
}
}  // namespace detail

/// Reads a reference from CSV with a header row naming the columns: t, q0..q{nq-1},
/// v0..v{nq-1}, u0..u{nu-1} in any order; other columns are ignored except `segment`. Event
/// times are where the time repeats (the two sides of an event) or where `segment` changes.
/// write_csv's output reads back exactly (17 significant digits). Throws InvalidArgument on a
/// missing column, a malformed number or a bad sample (ImportedReference::validate).
template <Scene S>
ImportedReference<S> read_reference_csv(std::istream& in) {
  constexpr int nq = S::nq, nu = S::nu;
  ImportedReference<S> ref;
  std::string line;
  std::vector<std::string> fields;
  SALTUS_REQUIRE(static_cast<bool>(std::getline(in, line)), "reference CSV: no header row");
  detail::split_csv_line(line, fields);
  auto column = [&](const std::string& name, bool required) {
    const auto it = std::find(fields.begin(), fields.end(), name);
    SALTUS_REQUIRE(it != fields.end() || !required, "reference CSV: no column '", name, "' in header '", line, "'");
    return it == fields.end() ? -1 : static_cast<int>(it - fields.begin());
  };
  const int t_col = column("t", true), segment_col = column("segment", false);
  std::vector<int> x_col(2 * nq), u_col(nu);
  for (int k = 0; k < nq; ++k) {
    x_col[k] = column("q" + std::to_string(k), true);
    x_col[nq + k] = column("v" + std::to_string(k), true);
  }
  for (int k = 0; k < nu; ++k) u_col[k] = column("u" + std::to_string(k), true);
  const std::size_t n_columns = fields.size();

  int row = 1;
  std::string previous_segment;
  auto number = [&](int col) {
    const std::string& f = fields[col];
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(f, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    SALTUS_REQUIRE(used == f.size() && !f.empty(), "reference CSV row ", row, ": '", f, "' is not a number");
    return value;
  };
  while (std::getline(in, line)) {
    ++row;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    detail::split_csv_line(line, fields);
    SALTUS_REQUIRE(fields.size() == n_columns, "reference CSV row ", row, ": ", fields.size(),
                   " fields, the header has ", n_columns);
    const double t = number(t_col);
    typename ImportedReference<S>::State x;
    typename ImportedReference<S>::Input u;
    for (int k = 0; k < 2 * nq; ++k) x[k] = number(x_col[k]);
    for (int k = 0; k < nu; ++k) u[k] = number(u_col[k]);
    const bool new_segment = segment_col >= 0 && !ref.t.empty() && fields[segment_col] != previous_segment;
    const bool event = !ref.t.empty() && (t == ref.t.back() || new_segment);
    if (event && (ref.event_times.empty() || ref.event_times.back() != t)) ref.event_times.push_back(t);
    if (segment_col >= 0) previous_segment = fields[segment_col];
    ref.segment.push_back(ref.segment.empty() ? 0 : ref.segment.back() + (event ? 1 : 0));
    ref.t.push_back(t);
    ref.x.push_back(x);
    ref.u.push_back(u);
  }
  ref.validate();
  return ref;
}

}  // namespace saltus
