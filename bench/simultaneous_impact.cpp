// simultaneous_impact: conewise jump gains of simultaneous impacts (sensitivity/conewise_gain.hpp)
// on the scene library's flat landings, per case:
//   guards                 m, the guards that fire together at the nominal event
//   pieces                 m!, the activation orders a perturbation could produce
//   realisable_pieces      orders realised by an open cone of perturbations: the leaves of the
//                          micro-event tree, all built (the others are reported by kind in
//                          `unrealisable_orders`: sent_away, empty_cone, no_longer_a_guard)
//   nominal_outcome_pieces realisable pieces that end in the nominal post-event state and mode (their
//                          prediction continues on the reference; the others end elsewhere at
//                          zeroth order: the impact map is discontinuous at the simultaneous event)
//   min_slope              smallest fitted log-log slope of the first-order prediction's remainder
//                          over eps = 1e-2..1e-6 with each sampled cone's own piece, against the
//                          piece's own outcome at T = t* + 0.02 s (plank-box; for the spatial box
//                          eps = 3e-5..3e-7 at T = t* + 0.1 ms: its cascades of re-touchdowns last
//                          ~1.6 eps s and leave corners that land again ~0.2 ms later; its
//                          perturbed runs use simultaneity 1e-13 s and gap_tolerance 1e-12 m, else
//                          the simulator lumps the cascade's micro-events at eps <= 1e-5..1e-6)
//                          (piece_remainder), fitted above the integration floor (points at least
//                          30x the smallest remainder, remainder_slope.hpp); `cones_sampled` cones
//   wrong_piece_slope      largest slope over the three smallest eps (1e-4..1e-6; spatial box 3e-6..3e-7)
//                          when another piece is applied, the one with
//                          the nearest outcome (about 1: a wrong first-order term; about 0: a wrong
//                          outcome)
//   max_face_discontinuity max |H_a(p) - H_b(p)| / |p| at points of shared cone faces between pieces
//                          with the same outcome (ConewiseJumpGain::face_discontinuity, 200
//                          directions; `faces` points checked, 0 when no two pieces share one)
//   build_us_per_piece     wall time of build_all() over the realisable pieces, microseconds
//   evaluate_us            wall time of one evaluate(z, v) once the pieces are built
//   max_micro_events       the longest order (re-touchdowns count: a corner landing twice is two)
//   twin_max_error         largest relative difference max|G_z,twin - G_z| / max|G_z| over the
//                          pieces whose twin (numerical_conewise_piece: one-sided differences inside
//                          the cone) ran; `twin_failed` pieces whose perturbed runs ended elsewhere
//   twin_ms                wall time of one twin, milliseconds
//   error                  (only when present) the gain refused the event: the exception's message
// Plain main; `--json` prints one JSON object, otherwise a table. SALTUS_BENCH_VERBOSE=1 prints, for a
// cone whose perturbed runs do not keep the piece's structure, each eps's events count and final
// mode (SALTUS_BENCH_EVENTS=1: each run's events too), and every twin that failed.
#include "remainder_slope.hpp"
#include "scenes/references.hpp"
#include <saltus/sensitivity/prediction_check.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iomanip>
#include <iostream>
#include <map>
#include <random>

namespace {

using namespace saltus;
using Clock = std::chrono::steady_clock;

struct Row {
  std::string name;
  int guards = 0, orders = 0, pieces = 0, realisable = 0, cones_sampled = 0, failed_runs = 0, faces = 0;
  int max_micro_events = 0, twin_failed = 0;
  double twin_error = NAN, twin_ms = NAN;
  std::map<std::string, int> unrealisable;
  std::vector<std::string> piece_lines;  ///< order: post-event mode, post-state difference
  std::string nominal_mode;
  std::string error;  ///< the gain refused the event (the exception's message), nothing measured
  double min_slope = NAN, wrong_slope = NAN, face = NAN, build_us = NAN, evaluate_us = NAN;
};

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

const char* reason_name(UnrealisableOrder::Reason r) {
  switch (r) {
    case UnrealisableOrder::Reason::SentAway: return "sent_away";
    case UnrealisableOrder::Reason::NoLongerAGuard: return "no_longer_a_guard";
    case UnrealisableOrder::Reason::EmptyCone: return "empty_cone";
  }
  return "?";
}

/// Where the cases differ: the time after t* at which a prediction is compared, the eps of the
/// remainder fits, and the twin's window and step (conewise pieces with re-touchdowns end with
/// corners moving away slowly, which land again ~0.2 ms later: everything must happen before).
struct Scales {
  double after = 0.02;
  std::vector<double> eps = default_prediction_eps();
  double twin_window = 1e-3, twin_step = 1e-4;
  /// The perturbed runs' simultaneity window (s) and gap tolerance (m): a cascade whose micro-events
  /// are separated by times and gaps shrinking like eps is lumped by the default windows (1e-9 s,
  /// 1e-9 m) at small eps (the spatial box: 5 of 8 cones at eps <= 1e-5..1e-6).
  double simultaneity = SimulationOptions{}.simultaneity;
  double gap_tolerance = ImpactOptions{}.gap_tolerance;
};

template <Scene S>
Row measure_body(const std::string& name, const S& scene, const Vec<2 * S::nq>& x0, const InputLaw<S>& input,
                 double t_final, int samples, const Scales& scales) {
  const double after = scales.after;
  constexpr int nx = 2 * S::nq, nu = S::nu;
  const SimulationOptions options = references::tight();
  Simulator<S> sim(scene, options);
  const auto traj = sim.run(x0, 0.0, t_final, input);
  Row row;
  row.name = name;
  if (traj.events.empty() || traj.events[0].transitions.front().guards.size() < 2) {
    std::cerr << name << ": the reference has no simultaneous first event\n";
    return row;
  }
  const Event<S>& ev = traj.events[0];
  row.guards = static_cast<int>(ev.transitions.front().guards.size());
  row.nominal_mode = describe(scene, ev.mode_after);
  row.orders = 1;
  for (int k = 2; k <= row.guards; ++k) row.orders *= k;
  ConewiseGainOptions copt;
  copt.simulation = options;
  {  // build time on a fresh gain
    ConewiseJumpGain<S> fresh(scene, ev, traj.input, copt);
    const auto start = Clock::now();
    row.pieces = fresh.build_all();
    row.build_us = 1e6 * seconds_since(start) / std::max(1, row.pieces);
    for (const auto* p : fresh.pieces()) {
      row.realisable += p->nominal_outcome;
      std::string order;
      for (const auto& group : p->order) {
        order += order.empty() ? "" : " -> ";
        for (std::size_t k = 0; k < group.size(); ++k) order += (k ? "+" : "") + scene.contact(group[k].contact).name;
      }
      row.piece_lines.push_back(order + ": " + describe(scene, p->mode_after) + ", post-state difference " +
                                std::to_string(p->post_state_difference));
    }
    for (const auto& u : fresh.unrealisable_orders()) ++row.unrealisable[reason_name(u.reason)];
    NumericalJumpGainOptions twin;
    twin.simulation = options;
    twin.window = scales.twin_window;
    twin.cone_step = scales.twin_step;
    double twin_seconds = 0.0;
    int twins = 0;
    for (const auto* p : fresh.pieces()) {
      row.max_micro_events = std::max(row.max_micro_events, static_cast<int>(p->order.size()));
      const auto start = Clock::now();
      try {
        const auto numeric = numerical_conewise_piece(scene, traj, 0, *p, twin);
        const double e = (numeric.G_z - p->G_z).cwiseAbs().maxCoeff() / p->G_z.cwiseAbs().maxCoeff();
        row.twin_error = std::isnan(row.twin_error) ? e : std::max(row.twin_error, e);
        twin_seconds += seconds_since(start);
        ++twins;
      } catch (const NumericalFailure& err) {
        ++row.twin_failed;
        if (std::getenv("SALTUS_BENCH_VERBOSE")) std::cerr << name << ": twin failed: " << err.what() << "\n";
      }
    }
    if (twins > 0) row.twin_ms = 1e3 * twin_seconds / twins;
    row.face = fresh.face_discontinuity(200, &row.faces);
    std::mt19937 rng(3);
    std::normal_distribution<double> normal;
    Vec<nx> z;
    Vec<nu> v;
    long calls = 0;
    const auto t0 = Clock::now();
    double elapsed = 0;
    do {
      for (auto& c : z) c = normal(rng);
      for (auto& c : v) c = normal(rng);
      const Vec<nx> h = fresh.evaluate(z, v);
      if (!h.allFinite()) std::abort();
      ++calls;
    } while ((elapsed = seconds_since(t0)) < 0.2);
    row.evaluate_us = 1e6 * elapsed / static_cast<double>(calls);
  }
  LinearisationOptions lopt;
  lopt.simulation = options;
  LinearisedSystem<S> lin(scene, traj, lopt);
  ConewiseJumpGain<S>& gain = lin.conewise_gain(0);
  gain.build_all();
  const double T = ev.t + after;
  SimulationOptions perturbed_options = options;
  perturbed_options.simultaneity = scales.simultaneity;
  perturbed_options.impact.gap_tolerance = scales.gap_tolerance;
  Simulator<S> perturbed_sim(scene, perturbed_options);
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  std::map<const ConewisePiece<S>*, bool> sampled;
  double min_slope = INFINITY, wrong_slope = -INFINITY;
  const auto zero = [](double) { return Vec<nu>::Zero().eval(); };
  for (int s = 0; s < samples && static_cast<int>(sampled.size()) < row.pieces; ++s) {
    Vec<nx> z0;
    for (auto& c : z0) c = normal(rng);
    const Vec<nx> z_minus = lin.propagate(0, z0, zero, ev.t);
    const ConewisePiece<S>& own = gain.piece(z_minus, Vec<nu>::Zero());
    if (sampled.count(&own)) continue;
    sampled[&own] = true;
    // Another piece, with the same outcome if there is one (then only its first-order term is wrong).
    const ConewisePiece<S>* other = nullptr;
    for (const auto* q : gain.pieces())
      if (q != &own && (!other || (q->x_plus - own.x_plus).norm() < (other->x_plus - own.x_plus).norm())) other = q;
    try {
      const RemainderFit right = piece_remainder(lin, perturbed_options, 0, z0, own, T, scales.eps);
      if (!right.structure_matched) {
        if (std::getenv("SALTUS_BENCH_VERBOSE")) {
          for (std::size_t k = 0; k < scales.eps.size(); ++k) {
            const auto run = perturbed_sim.run(Vec<nx>(x0 + scales.eps[k] * z0), 0.0, T, input);
            std::cerr << name << ": eps " << scales.eps[k] << ": " << run.events.size() << " events before T (piece: "
                      << own.order.size() << " micro-events), remainder " << right.remainder[k] << ", final mode "
                      << describe(scene, run.segments.back().mode) << "\n";
            if (std::getenv("SALTUS_BENCH_EVENTS"))
              for (const auto& e : run.events) {
                std::cerr << "    t - t* = " << e.t - ev.t << ":";
                for (const auto& tr : e.transitions)
                  for (const auto& g : tr.guards) std::cerr << " " << scene.contact(g.contact).name;
                std::cerr << " -> " << describe(scene, e.mode_after) << "\n";
              }
          }
        }
        ++row.failed_runs;
        continue;
      }
      ++row.cones_sampled;
      min_slope = std::min(min_slope, bench::slope_above_floor(right.eps, right.remainder).slope);
      if (other) {
        const RemainderFit wrong = piece_remainder(lin, perturbed_options, 0, z0, *other, T, scales.eps);
        // Its first-order error shows at the small eps (at the large ones the common eps^2 term
        // can still dominate when the pieces differ little along this perturbation).
        const std::vector<double> e3(wrong.eps.end() - 3, wrong.eps.end()), r3(wrong.remainder.end() - 3, wrong.remainder.end());
        wrong_slope = std::max(wrong_slope, fitted_log_slope(e3, r3));
      }
    } catch (const Error& err) {
      std::cerr << name << ": perturbed run failed: " << err.what() << "\n";
      ++row.failed_runs;
    }
  }
  if (row.cones_sampled > 0) row.min_slope = min_slope;
  if (std::isfinite(wrong_slope)) row.wrong_slope = wrong_slope;
  return row;
}

/// measure_body, or a row carrying the error when the gain refuses the event.
template <Scene S>
Row measure(const std::string& name, const S& scene, const Vec<2 * S::nq>& x0, const InputLaw<S>& input,
            double t_final, int samples, const Scales& scales) {
  try {
    return measure_body(name, scene, x0, input, t_final, samples, scales);
  } catch (const ContactProblemFailure& e) {
    Row row;
    row.name = name;
    row.error = e.what();
    std::cerr << name << ": " << e.what() << "\n";
    return row;
  }
}

}  // namespace

int main(int argc, char** argv) {
  const bool json = argc > 1 && std::strcmp(argv[1], "--json") == 0;
  std::vector<Row> rows;
  {
    scenes::PlankBox plank_box;
    auto input = open_loop<scenes::PlankBox>([&](double) { return plank_box.lowering_input(); });
    for (const double vx : {0.0, 0.3}) {
      Vec<8> x0 = plank_box.flat_state();
      x0[4] = vx;
      rows.push_back(measure(vx == 0 ? "plank_box flat landing, stick" : "plank_box flat landing, slip", plank_box, x0,
                             InputLaw<scenes::PlankBox>(input), 0.3, 200, Scales{}));
      std::cerr << "done: " << rows.back().name << "\n";
    }
  }
  {
    scenes::SpatialBox box;
    // The cascade lasts ~1.6 eps s per unit of gap deviation; its slowest corners land again
    // ~0.2 ms after it: compare at t* + 0.1 ms with eps <= 3e-5.
    Scales spatial;
    spatial.after = 1e-4;
    spatial.eps = {3e-5, 1e-5, 3e-6, 1e-6, 3e-7};
    spatial.twin_window = 1e-4;
    spatial.twin_step = 1e-5;
    spatial.simultaneity = 1e-13;
    spatial.gap_tolerance = 1e-12;
    for (const double vx : {0.0, 0.5}) {
      Vec<12> x0 = Vec<12>::Zero();
      x0[2] = 0.5 * box.parameters().size[2] + 0.02;
      x0[6] = vx;
      rows.push_back(measure(vx == 0 ? "spatial_box flat on four corners, stick" : "spatial_box flat on four corners, slip",
                             box, x0, zero_input<scenes::SpatialBox>(), 0.1, 400, spatial));
      std::cerr << "done: " << rows.back().name << "\n";
    }
  }
  const auto number = [](double x) -> nlohmann::ordered_json {
    if (std::isnan(x)) return nullptr;
    return x;
  };
  if (json) {
    nlohmann::ordered_json out = nlohmann::ordered_json::object();
    for (const Row& r : rows) {
      nlohmann::ordered_json unrealisable = nlohmann::ordered_json::object();
      for (const auto& [k, n] : r.unrealisable) unrealisable[k] = n;
      if (!r.error.empty()) {  // refused: nothing was measured
        out[r.name] = {{"error", r.error}};
        continue;
      }
      out[r.name] = {{"guards", r.guards},
                     {"pieces", r.orders},
                     {"realisable_pieces", r.pieces},
                     {"nominal_outcome_pieces", r.realisable},
                     {"unrealisable_orders", unrealisable},
                     {"cones_sampled", r.cones_sampled},
                     {"failed_runs", r.failed_runs},
                     {"min_slope", number(r.min_slope)},
                     {"wrong_piece_slope", number(r.wrong_slope)},
                     {"max_face_discontinuity", number(r.face)},
                     {"faces", r.faces},
                     {"build_us_per_piece", number(r.build_us)},
                     {"evaluate_us", number(r.evaluate_us)},
                     {"max_micro_events", r.max_micro_events},
                     {"twin_max_error", number(r.twin_error)},
                     {"twin_failed", r.twin_failed},
                     {"twin_ms", number(r.twin_ms)}};
    }
    std::cout << out.dump(2) << "\n";
    return 0;
  }
  std::cout << std::left << std::setw(42) << "case" << std::right << std::setw(7) << "guards" << std::setw(7)
            << "orders" << std::setw(11) << "realisable" << std::setw(9) << "nominal" << std::setw(7) << "cones"
            << std::setw(10) << "min_slope" << std::setw(12) << "wrong_slope" << std::setw(12) << "face_jump"
            << std::setw(14) << "build_us/pc" << std::setw(12) << "evaluate_us" << std::setw(8) << "depth"
            << std::setw(11) << "twin_err" << std::setw(12) << "twin_failed" << std::setw(9) << "twin_ms" << "\n";
  for (const Row& r : rows) {
    if (!r.error.empty()) {
      std::cout << std::left << std::setw(42) << r.name << " refused: " << r.error << "\n";
      continue;
    }
    std::cout << std::left << std::setw(42) << r.name << std::right << std::setw(7) << r.guards << std::setw(7)
              << r.orders << std::setw(11) << r.pieces << std::setw(9) << r.realisable << std::setw(7)
              << r.cones_sampled << std::setw(10) << std::setprecision(3) << r.min_slope << std::setw(12)
              << r.wrong_slope << std::setw(12) << std::setprecision(2) << r.face << std::setw(14)
              << std::setprecision(4) << r.build_us << std::setw(12) << r.evaluate_us << std::setw(8)
              << r.max_micro_events << std::setw(11) << std::setprecision(2) << r.twin_error << std::setw(12)
              << r.twin_failed << std::setw(9) << std::setprecision(3) << r.twin_ms << "\n";
    for (const auto& [k, n] : r.unrealisable) std::cout << "    unrealisable (" << k << "): " << n << "\n";
    std::cout << "    nominal post-event mode: " << r.nominal_mode << "\n";
    for (const auto& line : r.piece_lines) std::cout << "    piece " << line << "\n";
    if (r.failed_runs) std::cout << "    failed perturbed runs: " << r.failed_runs << "\n";
  }
  return 0;
}
