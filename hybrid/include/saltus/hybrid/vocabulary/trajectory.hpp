// A hybrid trajectory: smooth segments (a mode, a time interval, the dense output of x and the
// input law that drove it) separated by events (the time, the guards that fired, x- and x+, the
// modes before and after, and every transition of a chain at that instant). Segment i ends at
// event i; segment i + 1 starts there.
#pragma once

#include <saltus/hybrid/vocabulary/contact_force.hpp>
#include <saltus/hybrid/vocabulary/dense_output.hpp>
#include <saltus/hybrid/vocabulary/guard.hpp>
#include <saltus/hybrid/vocabulary/impact_mode.hpp>
#include <saltus/hybrid/vocabulary/input_law.hpp>
#include <saltus/hybrid/vocabulary/mode.hpp>

#include <algorithm>
#include <iomanip>
#include <istream>
#include <ostream>
#include <string>
#include <vector>

namespace saltus {

template <Scene S>
struct Segment {
  Mode<S::nc> mode;
  double t_begin = 0.0, t_end = 0.0;
  DenseOutput<2 * S::nq> x;
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
};

template <Scene S>
struct Event {
  double t = 0.0;
  VecT<double, 2 * S::nq> x_minus, x_plus;
  Mode<S::nc> mode_before, mode_after;
  std::vector<Transition<S>> transitions;  ///< in the order applied (a chain has several)

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
  SimulationStatus status = SimulationStatus::Completed;
  double zeno_time = std::numeric_limits<double>::quiet_NaN();  ///< predicted accumulation time
  SimulationStatistics statistics;

  double t_begin() const { return segments.empty() ? 0.0 : segments.front().t_begin; }
  double t_end() const { return segments.empty() ? 0.0 : segments.back().t_end; }
  int segment_count() const { return static_cast<int>(segments.size()); }

  /// x on segment i at t (t within the segment's interval).
  State state(int i, double t) const {
    const auto& s = segment(i);
    SALTUS_DEMAND(t >= s.t_begin - 1e-12 * std::max(1.0, std::abs(t)) && t <= s.t_end + 1e-12 * std::max(1.0, std::abs(t)),
                  InvalidArgument, "t = ", t, " is outside segment ", i, " [", s.t_begin, ", ", s.t_end, "]");
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

  /// Samples every dt (and the two sides of every event, as two rows with the same t): t,
  /// segment, mode (quoted), q, v, u. read_reference_csv reads it back.
  void write_csv(std::ostream& os, double dt, const S& scene) const {
    os << std::setprecision(17) << "t,segment,mode";
    for (int k = 0; k < nq; ++k) os << ",q" << k;
    for (int k = 0; k < nq; ++k) os << ",v" << k;
    for (int k = 0; k < nu; ++k) os << ",u" << k;
    os << "\n";
    for (int i = 0; i < segment_count(); ++i) {
      const auto& s = segments[i];
      const int n = std::max(1, static_cast<int>(std::ceil((s.t_end - s.t_begin) / dt)));
      for (int k = 0; k <= n; ++k) {
        // The end points exactly (t_begin + (t_end - t_begin) * n / n may round past t_end).
        const double t = k == n ? s.t_end : s.t_begin + (s.t_end - s.t_begin) * k / n;
        const State x = state(i, t);
        const Input u = input_at(i, t);
        // The mode is quoted: a spatial slip direction is written "(dx,dy)".
        os << t << "," << i << ",\"" << describe(scene, s.mode) << "\"";
        for (int j = 0; j < nx; ++j) os << "," << x[j];
        for (int j = 0; j < nu; ++j) os << "," << u[j];
        os << "\n";
      }
    }
  }

  /// Segments (mode, interval) and events (time, guards, x-, x+, modes) as JSON.
  void write_json(std::ostream& os, const S& scene) const {
    os << std::setprecision(17) << "{\"status\": \"" << to_string(status) << "\", \"segments\": [";
    for (int i = 0; i < segment_count(); ++i) {
      const auto& s = segments[i];
      os << (i ? ", " : "") << "{\"mode\": \"" << describe(scene, s.mode) << "\", \"t_begin\": " << s.t_begin
         << ", \"t_end\": " << s.t_end << ", \"steps\": " << s.x.size() << "}";
    }
    os << "], \"events\": [";
    for (std::size_t e = 0; e < events.size(); ++e) {
      const auto& ev = events[e];
      os << (e ? ", " : "") << "{\"t\": " << ev.t << ", \"impact\": " << (ev.impact() ? "true" : "false")
         << ", \"guards\": [";
      const auto g = ev.guards();
      for (std::size_t k = 0; k < g.size(); ++k)
        os << (k ? ", " : "") << "{\"contact\": \"" << scene.contact(g[k].contact).name << "\", \"kind\": \""
           << to_string(g[k].kind) << "\"}";
      os << "], \"mode_before\": \"" << describe(scene, ev.mode_before) << "\", \"mode_after\": \""
         << describe(scene, ev.mode_after) << "\", \"x_minus\": [";
      for (int j = 0; j < nx; ++j) os << (j ? ", " : "") << ev.x_minus[j];
      os << "], \"x_plus\": [";
      for (int j = 0; j < nx; ++j) os << (j ? ", " : "") << ev.x_plus[j];
      os << "]}";
    }
    os << "], \"zeno_time\": ";
    if (std::isfinite(zeno_time))
      os << zeno_time;
    else
      os << "null";
    os << ", \"steps\": " << statistics.steps << ", \"rhs_evaluations\": " << statistics.rhs_evaluations
       << ", \"wall_seconds\": " << statistics.wall_seconds << "}\n";
  }

 private:
  const Segment<S>& segment(int i) const {
    SALTUS_DEMAND(i >= 0 && i < segment_count(), InvalidArgument, "segment index ", i, " out of range [0, ",
                  segment_count(), ")");
    return segments[i];
  }
  State final_state_ = State::Zero();
};

/// A reference produced elsewhere (another optimiser, an experiment): samples (t_k, x_k, u_k)
/// in time order and its event times. At an event the samples may repeat the time, x- first and
/// x+ second (as write_csv writes them). Polish it with polish() (simulator.hpp).
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
    SALTUS_DEMAND(t.size() >= 2, InvalidArgument, "an imported reference needs at least 2 samples, got ", t.size());
    SALTUS_DEMAND(x.size() == t.size() && u.size() == t.size(), InvalidArgument, "imported reference: ", t.size(),
                  " times but ", x.size(), " states and ", u.size(), " inputs");
    for (std::size_t k = 0; k < t.size(); ++k) {
      SALTUS_DEMAND(std::isfinite(t[k]) && x[k].allFinite() && u[k].allFinite(), InvalidArgument,
                    "imported reference: sample ", k, " (t = ", t[k], ") is not finite");
      SALTUS_DEMAND(k == 0 || t[k] >= t[k - 1], InvalidArgument, "imported reference: times decrease at sample ", k,
                    " (", t[k - 1], " then ", t[k], ")");
    }
    SALTUS_DEMAND(t.back() > t.front(), InvalidArgument, "imported reference spans no time");
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
  SALTUS_DEMAND(static_cast<bool>(std::getline(in, line)), InvalidArgument, "reference CSV: no header row");
  detail::split_csv_line(line, fields);
  auto column = [&](const std::string& name, bool required) {
    const auto it = std::find(fields.begin(), fields.end(), name);
    SALTUS_DEMAND(it != fields.end() || !required, InvalidArgument, "reference CSV: no column '", name, "' in header '",
                  line, "'");
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
    SALTUS_DEMAND(used == f.size() && !f.empty(), InvalidArgument, "reference CSV row ", row, ": '", f,
                  "' is not a number");
    return value;
  };
  while (std::getline(in, line)) {
    ++row;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    detail::split_csv_line(line, fields);
    SALTUS_DEMAND(fields.size() == n_columns, InvalidArgument, "reference CSV row ", row, ": ", fields.size(),
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
