// Reading and writing trajectories (the data types are in trajectory.hpp): samples of t, mode,
// x and u as CSV (write_csv), read back as an ImportedReference (read_reference_csv); and the
// segments and events of a HybridTrajectory as JSON (to_json, write_json; nlohmann-json).
#pragma once

#include <algorithm>
#include <cmath>
#include <exception>
#include <iomanip>
#include <istream>
#include <nlohmann/json.hpp>
#include <ostream>
#include <saltus/hybrid/vocabulary/trajectory.hpp>
#include <string>
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

/// Segments (mode, interval) and events (time, guards, x-, x+, modes) as a JSON object:
///   status           "completed", "zeno" or "max-events"
///   segments         [{mode, t_begin, t_end, steps}]: mode as describe() writes it, the
///                    interval in s, steps the pieces of its dense output
///   events           [{t, impact, input_jump, guards: [{contact, kind}], mode_before, mode_after,
///                    x_minus, x_plus, impulses}]: input_jump true where a jump of the input at a
///                    breakpoint fired the event (Event::input_jump: its time is fixed, not a
///                    crossing), contact by its scene name, kind as to_string(GuardKind),
///                    x- and x+ of size 2 nq (q then v); impulses [{contact, normal, tangent}] of the
///                    contacts that took one, per impact of the event's chain in the order applied
///                    (N s; tangent in the contact's tangent coordinates, as many entries as it
///                    has tangents), empty without an impact
///   zeno_time        the predicted accumulation time in s, null when not finite
///   zeno_time_uncertainty  its uncertainty in s (HybridTrajectory), null when not finite
///   zeno_completions [{t, uncertainty, last_touchdown, contacts, event}]: the accumulations the run
///                    was continued past (ZenoCompletion): times in s (uncertainty null when not
///                    finite), the accumulating contacts by scene name, the completion's event index
///   steps, rhs_evaluations, wall_seconds   the simulation's statistics
/// Numbers keep their double values (a dump writes the shortest text that reads back exactly);
/// keys keep this order (nlohmann::ordered_json).
template <Scene S>
nlohmann::ordered_json to_json(const HybridTrajectory<S>& traj, const S& scene) {
  constexpr int nx = 2 * S::nq;
  auto state = [](const typename HybridTrajectory<S>::State& x) {
    auto a = nlohmann::ordered_json::array();
    for (int j = 0; j < nx; ++j) a.push_back(x[j]);
    return a;
  };
  auto segments = nlohmann::ordered_json::array();
  for (const auto& s : traj.segments)
    segments.push_back(
        {{"mode", describe(scene, s.mode)}, {"t_begin", s.t_begin}, {"t_end", s.t_end}, {"steps", s.x.size()}});
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
    events.push_back({{"t", ev.t},
                      {"impact", ev.impact()},
                      {"input_jump", ev.input_jump},
                      {"guards", std::move(guards)},
                      {"mode_before", describe(scene, ev.mode_before)},
                      {"mode_after", describe(scene, ev.mode_after)},
                      {"x_minus", state(ev.x_minus)},
                      {"x_plus", state(ev.x_plus)},
                      {"impulses", std::move(impulses)}});
  }
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  j["status"] = to_string(traj.status);
  j["segments"] = std::move(segments);
  j["events"] = std::move(events);
  j["zeno_time"] =
      std::isfinite(traj.zeno_time) ? nlohmann::ordered_json(traj.zeno_time) : nlohmann::ordered_json(nullptr);
  j["zeno_time_uncertainty"] = std::isfinite(traj.zeno_time_uncertainty)
                                   ? nlohmann::ordered_json(traj.zeno_time_uncertainty)
                                   : nlohmann::ordered_json(nullptr);
  auto completions = nlohmann::ordered_json::array();
  for (const ZenoCompletion& z : traj.zeno_completions) {
    auto contacts = nlohmann::ordered_json::array();
    for (int i : z.contacts) contacts.push_back(scene.contact(i).name);
    completions.push_back({{"t", z.t},
                           {"uncertainty", std::isfinite(z.uncertainty) ? nlohmann::ordered_json(z.uncertainty)
                                                                        : nlohmann::ordered_json(nullptr)},
                           {"last_touchdown", z.last_touchdown},
                           {"contacts", std::move(contacts)},
                           {"event", z.event}});
  }
  j["zeno_completions"] = std::move(completions);
  j["steps"] = traj.statistics.steps;
  j["rhs_evaluations"] = traj.statistics.rhs_evaluations;
  j["wall_seconds"] = traj.statistics.wall_seconds;
  return j;
}

/// to_json(traj, scene) on one line, then a newline. Throws nlohmann::json::type_error if a
/// contact name or mode description is not valid UTF-8.
template <Scene S>
void write_json(std::ostream& os, const HybridTrajectory<S>& traj, const S& scene) {
  os << to_json(traj, scene).dump() << "\n";
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
