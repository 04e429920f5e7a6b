// Tracking references with impacts: is the design locally stable, and by how much?
//
// For each case a reference (the point mass of the guiding example through its impact and
// release, the plank-box landing flat on both corners at once, the hopper through touchdown,
// stick, slip and lift-off, and a periodic hop of the point mass), a reference-spreading tracking
// controller (time-varying LQR along the reference with jumps, or PD), and one design that fails
// (the open-loop replay of the reference's input, or a negatively damped PD): the stability check
// (sensitivity/tracking.hpp: the amplification of the reference-spreading error over the horizon,
// with bounds over the conewise pieces of simultaneous events; the monodromy for the periodic
// hop) against 200 nonlinear closed-loop simulations from perturbed initial states on all cores.
//
//   tracking_stability            the table
//   tracking_stability --json     the same as JSON on stdout (progress on stderr):
//     {"cases": [{"name", "design", "verdict", "upper_bound", "lower_bound", "predicted_rate",
//                 "observed_rate", "runs", "kept_event_sequence", "failed", "agree", "seconds",
//                 "monte_carlo_seconds", ...}], "parallel_speedup": {...}}
// Agreement (monte_carlo_agrees, saltus/sensitivity/analysis/reference_analysis.hpp): the runs that
// keep the nominal event sequence all shrink (verdict stable) or the worst grows (unstable), their
// observed amplification is the first-order one within 5 % (|log(observed / predicted)| <= 0.05),
// and the largest observed rate is not above the predicted bound (1e-3 1/s slack).
#include "scenes/plank_box_tracking.hpp"
#include "scenes/references.hpp"

#include <saltus/sensitivity/sensitivity.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <optional>
#include <thread>

using namespace saltus;
using json = nlohmann::ordered_json;

namespace {

json number(double x) {
  if (!std::isfinite(x)) return nullptr;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return std::strtod(buf, nullptr);
}

template <Scene S>
LinearisationOptions signal_linearisation(const SimulationOptions& simulation) {
  LinearisationOptions o;
  o.gains.feedback = FeedbackTreatment::Signal;  // the tracker replaces the reference's own law
  o.simulation = simulation;
  o.spreading.before = o.spreading.after = 0.1;
  return o;
}

struct CaseResult {
  json row;
  bool agree = false;
};

/// One design on one reference: the check, then the Monte Carlo batch.
/// How a case is run: the closed loop's variational tolerances and the plant's simulation
/// options (default: the linearisation's and the reference's).
template <Scene S>
struct Numerics {
  std::optional<detail::OdeTolerances> variational;
  std::optional<SimulationOptions> plant;
};

template <Scene S>
CaseResult run_case(const std::string& name, const std::string& design, const references::Reference<S>& ref,
                    const LinearisedSystem<S>& ol, const GainSchedule<S>& gains, const StabilityOptions<S>& check,
                    MonteCarloOptions<S> mc, bool periodic = false, double period = 0.0, const Numerics<S>& numerics = {}) {
  ReferenceSpreadingController<S> controller(ol.reference(), gains);
  const auto t_check = std::chrono::steady_clock::now();
  ClosedLoopLinearisation<S> cl(ol, gains, numerics.variational);
  StabilityVerdict verdict;
  double upper, lower, predicted_rate, seconds;
  json extra;
  if (periodic) {
    const PeriodicStabilityReport r = check_periodic_stability(cl, period, check);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_check).count();
    verdict = r.verdict;
    upper = r.spectral_radius_upper;
    lower = r.spectral_radius_lower;
    predicted_rate = std::log(upper) / period;
    extra["period"] = number(period);
    extra["bounds_of"] = "spectral radius of the monodromy";
  } else {
    const StabilityReport r = check_stability(cl, check, mc.t_final);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_check).count();
    verdict = r.verdict;
    upper = r.upper_bound;
    lower = r.lower_bound;
    predicted_rate = r.upper_rate;
    extra["bounds_of"] = "amplification a(T)";
    extra["peak_amplification"] = number(r.peak_upper);
    extra["peak_time"] = number(r.peak_time);
    extra["tail_amplification"] = number(r.tail_amplification);
    extra["piece_sequences"] = r.sequences;
  }
  mc.progress = &std::cerr;
  const MonteCarloReport m = monte_carlo(ref.scene, numerics.plant ? *numerics.plant : ref.options, controller, cl, mc);
  const double horizon = (mc.t_final > 0 ? mc.t_final : ol.t_end(ol.segment_count() - 1)) - ol.t_begin(0);
  // The finite-horizon bound is on a(T); the periodic one on the asymptotic rate, which a finite
  // batch does not bound from above (transients): there only the sampled prediction is compared.
  CaseResult out;
  out.agree = monte_carlo_agrees(verdict, m, predicted_rate, !periodic);
  json row;
  row["name"] = name;
  row["design"] = design;
  row["verdict"] = to_string(verdict);
  row["upper_bound"] = number(upper);
  row["lower_bound"] = number(lower);
  row["predicted_rate"] = number(predicted_rate);
  row["observed_rate"] = number(m.observed_rate_max);
  row["observed_rate_median"] = number(m.observed_rate_median);
  row["predicted_rate_of_the_runs"] = number(m.predicted_rate_max);
  row["max_log_discrepancy"] = number(m.max_log_discrepancy);
  row["horizon"] = number(horizon);
  row["runs"] = m.runs;
  row["kept_event_sequence"] = m.kept_event_sequence;
  row["failed"] = m.failed;
  row["failure_reasons"] = m.failure_reasons;
  row["grew"] = m.grew;
  row["shrank"] = m.shrank;
  row["agree"] = out.agree;
  row["seconds"] = number(seconds);
  row["monte_carlo_seconds"] = number(m.seconds);
  row["threads"] = m.threads;
  row["perturbation_size"] = number(mc.size);
  row["variational_tolerance"] = number(cl.tolerances().relative);
  for (auto& [k, v] : extra.items()) row[k] = v;
  out.row = row;
  return out;
}

Mat<2, 4> point_mass_pd(double kp, double kd) {
  return pd_gain<scenes::PointMass>(kp * Mat<2, 2>::Identity(), kd * Mat<2, 2>::Identity());
}

}  // namespace

int main(int argc, char** argv) {
  const bool as_json = argc > 1 && std::strcmp(argv[1], "--json") == 0;
  json cases = json::array();
  bool all_agree = true;
  const auto add = [&](CaseResult r) {
    all_agree = all_agree && r.agree;
    const json& j = r.row;
    if (!as_json)
      std::printf("%-26s %-30s %-9s a in [%-9.4g, %-9.4g] rate pred %-9.3g obs %-9.3g kept %3d/%-3d failed %d  %s  "
                  "check %.3f s, MC %.2f s\n",
                  j["name"].get<std::string>().c_str(), j["design"].get<std::string>().c_str(),
                  j["verdict"].get<std::string>().c_str(), j["lower_bound"].is_null() ? NAN : j["lower_bound"].get<double>(),
                  j["upper_bound"].is_null() ? NAN : j["upper_bound"].get<double>(),
                  j["predicted_rate"].is_null() ? NAN : j["predicted_rate"].get<double>(),
                  j["observed_rate"].is_null() ? NAN : j["observed_rate"].get<double>(),
                  j["kept_event_sequence"].get<int>(), j["runs"].get<int>(), j["failed"].get<int>(),
                  r.agree ? "agree" : "DISAGREE", j["seconds"].get<double>(), j["monte_carlo_seconds"].get<double>());
    cases.push_back(j);
  };

  // ---- point mass, Example 3: impact into closed contact, sliding, release ------------------
  {
    using S = scenes::PointMass;
    const auto ref = references::example3();
    const LinearisedSystem<S> ol(ref.scene, ref.trajectory, signal_linearisation<S>(ref.options));
    LqrWeights<S> w;
    w.R *= 0.1;
    const LqrDesign<S> lqr = lqr_design(ol, w);
    MonteCarloOptions<S> mc;
    add(run_case<S>("point mass (Example 3)", "LQR, Q = I, R = 0.1 I", ref, ol, lqr.gains, {}, mc));
    add(run_case<S>("point mass (Example 3)", "open-loop replay (K = 0)", ref, ol, GainSchedule<S>(3, Mat<2, 4>::Zero()),
                    {}, mc));
  }

  // ---- plank-box landing flat: a simultaneous impact (conewise, two cones) -------------------
  {
    using S = scenes::PlankBox;
    references::Reference<S> ref{"plank-box flat landing", S{}, references::tight(), {}};
    Simulator<S> sim(ref.scene, ref.options);
    const Vec<3> u = ref.scene.lowering_input();
    ref.trajectory = sim.run(ref.scene.flat_state(), 0.0, 0.3, open_loop<S>([u](double) { return u; }));
    const LinearisedSystem<S> ol(ref.scene, ref.trajectory, signal_linearisation<S>(ref.options));
    Mat<3, 4> Kp = Mat<3, 4>::Zero(), Kd = Mat<3, 4>::Zero();
    Kp.leftCols<3>() = Vec<3>(60.0, 60.0, 6.0).asDiagonal();
    Kd.leftCols<3>() = Vec<3>(10.0, 10.0, 1.0).asDiagonal();
    // Deviations of the box's initial state (the plank starts at rest), measured on the box; the
    // LQR weights on the box (scenes/plank_box_tracking.hpp, shared with the optimised landing's analysis).
    const ReferenceAnalysisOptions<S> box_tracking = scenes::plank_box_tracking(200);
    const StabilityOptions<S>& check = box_tracking.stability;
    const MonteCarloOptions<S>& mc = box_tracking.monte_carlo;
    const int n = ol.segment_count();
    const LqrDesign<S> lqr = lqr_design(ol, box_tracking.design.weights);  // the cost-to-go jump through the worst piece
    add(run_case<S>("plank-box (flat landing)", box_tracking.design.name, ref, ol, lqr.gains, check, mc));
    add(run_case<S>("plank-box (flat landing)", "box PD (60, 10; 6, 1)", ref, ol, GainSchedule<S>(n, pd_gain<S>(Kp, Kd)),
                    check, mc));
    add(run_case<S>("plank-box (flat landing)", "open-loop replay (K = 0)", ref, ol, GainSchedule<S>(n, Mat<3, 8>::Zero()),
                    check, mc));
  }

  // ---- hopper: touchdown into stick, stick -> slip, release -----------------------------------
  double one_thread = 0.0, all_threads = 0.0;
  int threads = 1;
  {
    using S = scenes::Hopper;
    const auto ref = references::hopper_push_off();
    // Extensions of 20 ms (the event shifts at eps = 1e-5 are microseconds; the reference's own
    // law is a PD whose backward extension grows fast, 0.1 s costs 1.7 s), the check at 1e-9
    // (0.57 s against 3.2 s at 1e-10; same verdict and a(T) to 4 digits) and the plant at 1e-10.
    LinearisationOptions lo = signal_linearisation<S>(ref.options);
    lo.spreading.before = lo.spreading.after = 0.02;
    const LinearisedSystem<S> ol(ref.scene, ref.trajectory, lo);
    Numerics<S> numerics;
    numerics.variational = detail::OdeTolerances{1e-9, 1e-10, 1e-4, 10'000'000};
    numerics.plant = ref.options;
    numerics.plant->integrator.relative_tolerance = 1e-10;
    numerics.plant->integrator.absolute_tolerance = 1e-11;
    // Joint PD with the same gains in every segment. (An LQR along this reference has gains that
    // jump at the lift-off; the plant's input then jumps by O(eps) at its own release, where the
    // foot leaves with zero normal acceleration, and in 40 of 200 runs the foot touches down
    // again at once: an event the reference does not have. Gains continuous across a release
    // avoid that.)
    const auto joint_pd = [](double kp, double kd) {
      Mat<2, 4> Kp = Mat<2, 4>::Zero(), Kd = Mat<2, 4>::Zero();
      Kp(0, 2) = Kp(1, 3) = kp;
      Kd(0, 2) = Kd(1, 3) = kd;
      return pd_gain<S>(Kp, Kd);
    };
    const int n = ol.segment_count();
    StabilityOptions<S> check;
    Mat<8, 8> joints = Mat<8, 8>::Zero();  // hip and knee angles and rates: what the torques regulate
    for (int k : {2, 3, 6, 7}) joints(k, k) = 1.0;
    check.output_weight = joints;
    MonteCarloOptions<S> mc;
    mc.output_weight = joints;
    mc.size = 1e-5;
    const GainSchedule<S> pd(n, joint_pd(100.0, 3.0));
    CaseResult r = run_case<S>("hopper (push-off)", "joint PD (100, 3)", ref, ol, pd, check, mc, false, 0.0, numerics);
    all_threads = r.row["monte_carlo_seconds"].get<double>();
    threads = r.row["threads"].get<int>();
    add(r);
    // (A stiffer joint PD, (300, 3), is called unstable with a(T) = 1.106 in its worst direction,
    // while none of 200 random perturbations grows (their largest rate is -0.08 1/s): the growing
    // directions are a thin set, as the gap between the bound and the sampled rates says. Not a
    // case a random batch can confirm, so not listed.)
    add(run_case<S>("hopper (push-off)", "open-loop replay (K = 0)", ref, ol, GainSchedule<S>(n, Mat<2, 8>::Zero()), check,
                    mc, false, 0.0, numerics));
    // The same batch on one thread: the parallel speed-up.
    mc.threads = 1;
    ReferenceSpreadingController<S> controller(ol.reference(), pd);
    ClosedLoopLinearisation<S> cl(ol, pd, numerics.variational);
    one_thread = monte_carlo(ref.scene, *numerics.plant, controller, cl, mc).seconds;
  }

  // ---- periodic hop of the point mass: monodromy ------------------------------------------
  {
    using S = scenes::PointMass;
    const double P = references::point_mass_hop_period;
    const auto ref = references::point_mass_hop(3.2 * P);
    const LinearisedSystem<S> ol(ref.scene, ref.trajectory, signal_linearisation<S>(ref.options));
    MonteCarloOptions<S> mc;
    mc.scale << 1.0, 0.0, 1.0, 0.0;  // horizontal only: the start is at rest on the table
    mc.t_final = 3 * P;
    const int n = ol.segment_count();
    add(run_case<S>("point mass (periodic hop)", "PD (10, 4)", ref, ol, GainSchedule<S>(n, point_mass_pd(10.0, 4.0)), {},
                    mc, true, P));
    add(run_case<S>("point mass (periodic hop)", "PD (10, -1): negative damping", ref, ol,
                    GainSchedule<S>(n, point_mass_pd(10.0, -1.0)), {}, mc, true, P));
  }

  json out;
  out["cases"] = cases;
  out["parallel_speedup"] = {{"case", "hopper joint PD (100, 3), 200 runs"},
                             {"threads", threads},
                             {"one_thread_seconds", number(one_thread)},
                             {"all_threads_seconds", number(all_threads)},
                             {"speedup", number(one_thread / all_threads)}};
  out["all_agree"] = all_agree;
  if (as_json) {
    std::cout << out.dump(2) << "\n";
  } else {
    std::printf("Monte Carlo on %d threads: %.2f s, one thread %.2f s: speed-up %.2f\n", threads, all_threads, one_thread,
                one_thread / all_threads);
  }
  return all_agree ? 0 : 1;
}
