// Accuracy of the FESD discretisation of the time-freezing system (timefreezing/) against closed
// forms, and the same Radau IIA scheme on a fixed grid, as the grid is refined.
//
//   fesd_accuracy [--json] [--budget SECONDS] [--scheme fesd|fixed] [--stages 1|2|3]
//                 [--finite-elements N1,N2,...] [--refine TARGET] [--contact-side WEIGHT]
//                 [--landing-only] [--ipopt NAME=VALUE]... [--kappa K] [--sigma0 S] [--progress]
//
// --finite-elements replaces the default N_fe = 1, 2, 4, 8 (the budget rule drops the last one).
// --refine sets MpccSolverOptions::Homotopy::complementarity_refinement (in (0, 1e-9)) for the guiding
// example: each control interval's converged homotopy goes on towards that residual.
// --contact-side sets FesdOptions::regularisation.contact_side (>= 0; scheme "fesd+side" when > 0) for both
// examples (default: 0 for the guiding example, the landing's own 1e-2); --landing-only runs the
// frictional landing alone. --ipopt passes an Ipopt option to
// every solve of both examples (as in hopper_ocp), --kappa K (in (0, 1)) and --sigma0 S (> 0) set
// the homotopy's MpccSolverOptions::Homotopy::kappa and sigma_0 (any of the three adds "+opts" to the scheme),
// --progress prints one line per Ipopt solve on stderr.
// SALTUS_BENCH_TRACE=1 prints, per configuration, the error of every element boundary's state
// against the closed form y(tau) (exact_state below): where along the horizon the error arises;
// and for the element that starts there its length, its stage points' ODE weight Theta and step
// functions alpha (gap, J_n v).
//
// --scheme and --stages restrict the guiding example to one scheme or one n_s (e.g. to rerun a
// dropped configuration with a larger --budget); the frictional landing runs only without them.
//
// GUIDING EXAMPLE (time-freezing paper, Example 3; tests/test_time_freezing.cpp): the point mass
// (m = 1, g = 9.81) from q0 = (0, 1), v0 = 0 under u = (7, 0) for t < 1 and u = (7, 2 g (t - 1))
// after, a_n = g, frictionless table, numerical horizon tau in [0, 3.5] split into 14 control
// intervals of 0.25 (tau = 2, where the input has its kink, is a control node), simulated with
// simulate_time_freezing (one MPCC per control interval) for n_s = 1, 2, 3 Radau IIA stages,
// N_fe = 1, 2, 4, 8 finite elements per control interval (h = 0.25 / N_fe) and two schemes:
//   fesd   switching.detection = true: free element lengths and cross-complementarity, the
//          heuristic step equilibration (rho_h sum (h - h0)^2, NOSNOC's default);
//   fixed  switching.detection = false: the same Radau IIA collocation on the uniform grid.
//
// Closed form (derivation). Free fall: q2 = 1 - g t^2 / 2, touchdown at t = sqrt(2/g) (= tau,
// the clock has run at speed 1) with v2 = -sqrt(2 g). Frozen phase: the auxiliary field
// v2' = a_n = g with the clock stopped, for sqrt(2 g) / g = sqrt(2/g) of numerical time: it ends
// at tau = 2 sqrt(2/g) with v = (7 sqrt(2/g), 0). Sliding on q2 = 0, v2 = 0: the Filippov
// combination theta (u2 - g) + (1 - theta) a_n = 0 of the ODE field (clock speed 1) and the
// auxiliary field (clock speed 0) gives the clock speed theta = g / (2 g - u2): 1/2 while u2 = 0,
// so t = 1 is reached at tau = 2 sqrt(2/g) + 2 (1 - sqrt(2/g)) = 2; after it theta =
// 1 / (2 (2 - t)), i.e. dtau = 2 (2 - t) dt, tau = 2 + 4 t - t^2 - 3 until u2 = g at t = 1.5
// (lift-off, tau = 2.75). Then the clock runs at speed 1 again and v2' = g (2 t - 3):
// v2 = g (t - 1.5)^2, q2 = g (t - 1.5)^3 / 3, up to t = 1.5 + (3.5 - 2.75) = 2.25 at tau = 3.5.
// Horizontally nothing acts but u1 = 7 (the auxiliary field is normal): q1 = 3.5 t^2, v1 = 7 t.
// So y(3.5) = (3.5 t^2, g (t - 1.5)^3 / 3, 7 t, g (t - 1.5)^2, t) at t = 2.25.
//
// Columns, per (scheme, n_s, N_fe):
//   elements        total finite elements, 14 N_fe
//   touchdown err   |t - sqrt(2/g)|, t the physical time of the first switch point of switching
//                   function 0 (the gap) in sim.switch_points
//   frozen-end err  |tau - 2 sqrt(2/g)|, tau of the first switch point of function 1 (J_n v)
//   lift-off err    |t - 1.5|, t the physical time of the LAST Release event of the recovered
//                   trajectory (sim.trajectory, recover_trajectory: the contact's mode read where
//                   its closing weight vanishes; after lift-off J_n v = g (t - 1.5)^2 > 0 stays
//                   positive, so the last release is the lift-off; the one closest to 1.5 would
//                   flatter a scheme with spurious releases). Until 2026-12-01 this column was
//                   |tau - 2.75| of the last switch point of function 1 (the mean step function
//                   rounded with 1e-6), which near this tangential lift-off reads the leftover
//                   step functions of degenerate elements (7.8e-6 at n_s = 2, 1,120 elements).
//                   When there is no release it is estimated from the elements (marked '~' in the
//                   table, "estimated" in the JSON): the last element boundary with tau > 2
//                   (inside the sliding phase) at which J_n v <= 1e-6, minus 2.75 (numerical time:
//                   the start of the element in which the normal velocity leaves zero for good;
//                   only good to about h).
//   final err       max |y(3.5) - exact| over (q1, q2, v1, v2, t)
//   conv, compl     every homotopy converged; the largest complementarity residual of the
//                   control intervals' MPCCs (MpccSolution::complementarity)
//   iters, seconds  total Ipopt iterations; wall time of simulate_time_freezing (steady_clock)
// A switch point is an element boundary where the mean step function alpha_m of the elements on
// either side, rounded to {0, 1/2, 1}, differs (simulation.hpp): on the fixed grid the active
// set may change inside an element, so its switch points sit at element boundaries next to the
// true switch and their error is of the order of h by construction.
//
// Observed order, per scheme and n_s: log(e2 / e1) / log(h2 / h1) for consecutive N_fe, e the
// final err. FESD should show the Radau order 2 n_s - 1, the fixed grid order 1 (bench/README.md
// reports what the run shows and what limits it).
//
// Budget: the configurations of one (scheme, n_s) run in increasing N_fe; when one of them takes
// more than the budget (--budget, default 30 s), the largest N_fe (8) of that (scheme, n_s) is
// not run, and the output says so ("dropped"). (Not every larger N_fe: the time is not monotone
// in N_fe; a configuration whose homotopy does not converge can take longer than the next one.)
//
// FRICTIONAL LANDING (NOSNOC's smallest time-freezing example; tests/test_time_freezing.cpp):
// g = 10, mu = 0.2, a_n = 20, q0 = (0, 1), v0 = (3, 0), 20 control intervals of 0.125, N_fe = 5,
// n_s = 2, FESD: the mass stops at x = 2.45 exactly; reported: |x_final - 2.45|, converged,
// complementarity, Ipopt iterations, seconds.
//
// --json prints exactly one JSON object on stdout: {"guiding_example": [{"scheme", "n_s",
// "finite_elements", "elements", "touchdown_time_error", "frozen_end_error", "lift_off_error",
// "lift_off_estimated", "final_state_error", "converged", "complementarity", "ipopt_iterations",
// "seconds"}, ...], "orders": [{"scheme", "n_s", "from_finite_elements", "to_finite_elements",
// "order"}, ...], "dropped": [{"scheme", "n_s", "finite_elements", "reason"}, ...],
// "frictional_landing": {"scheme", "stop_error", "converged", "complementarity", "ipopt_iterations",
// "seconds"}} (errors null when not measurable; frictional_landing null when not run). Without
// it, a table. One progress line per configuration goes to stderr either way. Exit status 0
// unless a simulation threw.
#include "scenes/point_mass.hpp"
#include "ocp_bench_support.hpp"
#include "scenes/time_freezing_examples.hpp"

#include <saltus/timefreezing/discretisation/fesd.hpp>
#include <saltus/timefreezing/mpcc/mpcc_solver.hpp>
#include <saltus/timefreezing/header_only.hpp>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

namespace {

using namespace saltus;
using namespace saltus::timefreezing;
using saltus::bench::parse_ipopt_option;
using scenes::PointMass;

constexpr double g = 9.81;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int control_intervals = 14;
constexpr double horizon = 3.5;

using Example3Input = scenes::Example3;

/// y(3.5) = (q1, q2, v1, v2, t) of Example 3 (file comment).
Vec<5> exact_final_state() { return scenes::Example3::final_state(); }

/// y(tau) = (q1, q2, v1, v2, t) of Example 3 at any numerical time in [0, 3.5] (file comment).
Vec<5> exact_state(double tau) {
  const double t_td = std::sqrt(2.0 / g);
  double t = 0.0, q2 = 0.0, v2 = 0.0, v1 = 0.0;
  if (tau <= t_td) {
    t = tau, q2 = 1.0 - 0.5 * g * t * t, v2 = -g * t;
  } else if (tau <= 2.0 * t_td) {
    t = t_td, v2 = -std::sqrt(2.0 * g) + g * (tau - t_td);  // frozen: the auxiliary field
  } else if (tau <= 2.0) {
    t = t_td + 0.5 * (tau - 2.0 * t_td);  // sliding, clock speed 1/2
  } else if (tau <= 2.75) {
    t = 2.0 - std::sqrt(3.0 - tau);  // sliding, tau = 4 t - t^2 - 1
  } else {
    t = 1.5 + (tau - 2.75), q2 = g * std::pow(t - 1.5, 3) / 3.0, v2 = g * (t - 1.5) * (t - 1.5);
  }
  v1 = 7.0 * t;
  return (Vec<5>() << 3.5 * t * t, q2, v1, v2, t).finished();
}

struct Row {
  std::string scheme;
  int stages = 0, finite_elements = 0, elements = 0;
  double touchdown = kNaN, frozen_end = kNaN, lift_off = kNaN, final_error = kNaN;
  bool lift_off_estimated = false;
  bool converged = false;
  double complementarity = kNaN;
  int iterations = 0;
  double seconds = kNaN;
  std::string error;  ///< the exception's message when the simulation threw
};

struct Dropped {
  std::string scheme;
  int stages = 0, finite_elements = 0;
  std::string reason;
};

struct Order {
  std::string scheme;
  int stages = 0, from = 0, to = 0;
  double order = kNaN;
};

/// A whole command-line argument as a finite number, NaN otherwise (so that "--contact-side --json"
/// is refused, not read as 0).
double parse_number(const char* text) {
  char* end = nullptr;
  const double x = std::strtod(text, &end);
  return end != text && *end == '\0' && std::isfinite(x) ? x : std::numeric_limits<double>::quiet_NaN();
}

/// MpccSolverOptions::Homotopy::complementarity_refinement of the guiding example's runs (--refine).
double refinement = 0.0;
/// FesdOptions::regularisation.contact_side of both examples' runs (--contact-side; < 0: the example's
/// own, 0 for the guiding example, 1e-2 for the frictional landing).
double contact_side = -1.0;
/// Solver overrides of both examples' runs: --ipopt NAME=VALUE (repeatable), --kappa K, --sigma0 S,
/// --progress (one line per Ipopt solve on stderr).
std::vector<timefreezing::IpoptOption> ipopt_overrides;
double kappa_override = 0.0, sigma0_override = 0.0;
bool progress = false;
void apply_solver_flags(timefreezing::MpccSolverOptions& solver) {
  solver.ipopt.options.insert(solver.ipopt.options.end(), ipopt_overrides.begin(), ipopt_overrides.end());
  if (kappa_override > 0.0) solver.homotopy.kappa = kappa_override;
  if (sigma0_override > 0.0) solver.homotopy.sigma_0 = sigma0_override;
  if (progress) solver.progress = &std::cerr;
}
/// "+opts" when --ipopt, --kappa or --sigma0 changed the solver.
std::string solver_suffix() {
  return ipopt_overrides.empty() && kappa_override == 0.0 && sigma0_override == 0.0 ? "" : "+opts";
}
/// The scheme's name with the options that change it.
std::string scheme_label(const std::string& scheme) {
  return scheme + (contact_side > 0.0 ? "+side" : "") + (refinement > 0.0 ? "+refine" : "") + solver_suffix();
}
/// The frictional landing's scheme: FESD with its own contact-side selection unless
/// --contact-side overrides it.
std::string landing_label() {
  const double side = contact_side >= 0.0 ? contact_side : scenes::FrictionalLanding::grid().regularisation.contact_side;
  return std::string("fesd") + (side > 0.0 ? "+side" : "") + solver_suffix();
}

Row run_guiding(const std::string& scheme, int stages, int finite_elements) {
  Row r;
  r.scheme = scheme_label(scheme);
  r.stages = stages;
  r.finite_elements = finite_elements;
  const TimeFreezingSystem<PointMass> system(PointMass(), g);
  FesdOptions o;
  o.grid.stages = stages;
  o.grid.control_intervals = control_intervals;
  o.grid.finite_elements = finite_elements;
  o.grid.horizon = horizon;
  o.switching.detection = scheme != "fixed";
  if (contact_side >= 0.0) o.regularisation.contact_side = contact_side;
  const auto start = std::chrono::steady_clock::now();
  MpccSolverOptions solver;
  solver.homotopy.complementarity_refinement = refinement;
  apply_solver_flags(solver);
  const auto sim = simulate_time_freezing(system, Vec<2>(0, 1), Vec<2>(0, 0), o, Example3Input{}, solver);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.elements = static_cast<int>(sim.element_lengths.size());
  r.converged = sim.converged();
  r.complementarity = sim.solution.complementarity;
  r.iterations = sim.solution.ipopt_iterations;
  r.final_error = (sim.final_state().head<5>() - exact_final_state()).cwiseAbs().maxCoeff();
  if (std::getenv("SALTUS_BENCH_TRACE")) {  // the error at every element boundary, per component
    std::fprintf(stderr, "  %s\n", sim.solution.message.c_str());
    for (std::size_t e = 0; e <= sim.element_lengths.size(); ++e) {
      const auto& p = sim.points[e * static_cast<std::size_t>(stages)];
      const Vec<5> err = p.y.template head<5>() - exact_state(p.tau);
      std::fprintf(stderr, "  tau %.9f  t %.9f  error q1 %+.2e q2 %+.2e v1 %+.2e v2 %+.2e t %+.2e", p.tau, p.y[4],
                   err[0], err[1], err[2], err[3], err[4]);
      // The element that starts here: its stage points' ODE weight Theta and step functions
      // (gap, J_n v).
      if (e < sim.element_lengths.size()) {
        std::fprintf(stderr, "  | h %.2e Theta", sim.element_lengths[e]);
        for (int r = 0; r < stages; ++r) std::fprintf(stderr, " %.9f", sim.points[1 + e * stages + r].ode_weight);
        std::fprintf(stderr, " alpha_gap,vn");
        for (int r = 0; r < stages; ++r) {
          const auto& a = sim.points[1 + e * stages + r].alpha;
          std::fprintf(stderr, " %.3g,%.3g", a[0], a[1]);
        }
      }
      std::fprintf(stderr, "\n");
    }
  }

  const double t_impact = std::sqrt(2.0 / g);
  const SwitchPoint* touchdown = nullptr;
  const SwitchPoint* frozen_end = nullptr;
  for (const SwitchPoint& s : sim.switch_points) {
    if (s.switching_function == 0 && !touchdown) touchdown = &s;
    if (s.switching_function == 1 && !frozen_end) frozen_end = &s;
  }
  const Event<PointMass>* release = nullptr;
  for (const auto& ev : sim.trajectory.events)
    for (const Guard& guard : ev.guards())
      if (guard.kind == GuardKind::Release) release = &ev;
  if (touchdown) r.touchdown = std::abs(touchdown->time - t_impact);
  if (frozen_end) r.frozen_end = std::abs(frozen_end->tau - 2.0 * t_impact);
  if (release) {
    r.lift_off = std::abs(release->t - 1.5);
  } else {
    // Estimate from the element boundaries (file comment). Point mass: J_n v = v2 = y[3].
    constexpr double still = 1e-6;
    double last_sliding = kNaN;
    for (std::size_t e = 0; e < sim.element_lengths.size(); ++e) {
      const auto& end = sim.points[(e + 1) * static_cast<std::size_t>(stages)];
      if (end.tau > 2.0 && end.tau < horizon - 1e-12 && end.y[3] <= still) last_sliding = end.tau;
    }
    r.lift_off = std::abs(last_sliding - 2.75);
    r.lift_off_estimated = true;
  }
  return r;
}

struct Landing {
  double stop_error = kNaN, complementarity = kNaN, seconds = kNaN;
  bool converged = false;
  int iterations = 0;
  std::string error;
};

Landing run_landing() {
  Landing l;
  using Case = scenes::FrictionalLanding;
  const auto start = std::chrono::steady_clock::now();
  timefreezing::FesdOptions grid = Case::grid();
  if (contact_side >= 0.0) grid.regularisation.contact_side = contact_side;
  MpccSolverOptions solver;
  apply_solver_flags(solver);
  const auto sim = simulate_time_freezing(Case::system(), Case::q0(), Case::v0(), grid, timefreezing::NoObjective{}, solver);
  l.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  l.stop_error = std::abs(sim.final_state()[0] - Case::stop);
  l.converged = sim.converged();
  l.complementarity = sim.solution.complementarity;
  l.iterations = sim.solution.ipopt_iterations;
  return l;
}

/// A JSON number with 4 significant digits (JSON has no NaN or infinity: those become null).
nlohmann::ordered_json number(double x) {
  if (!std::isfinite(x)) return nullptr;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4e", x);
  return std::strtod(buf, nullptr);
}

/// "%9.2e" or "-" for a value that could not be measured.
std::string cell(double x) {
  if (!std::isfinite(x)) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2e", x);
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  // One BLAS thread: Debian's Ipopt (through MUMPS and LAPACK) may link a threaded BLAS
  // (OpenBLAS), whose threads only compete for the cores on these small systems and make the
  // timings noisy. Set before any Ipopt call. Caveat: OpenBLAS reads the variable in its load-time
  // constructor, i.e. before main when libblas.so.3 resolves to it; for a fully effective setting
  // export OPENBLAS_NUM_THREADS=1 in the shell too (bench/README.md does). On the development
  // machine libblas.so.3 is the single-threaded reference BLAS, so it changes nothing there.
  setenv("OPENBLAS_NUM_THREADS", "1", 1);

  bool json = false;
  double budget = 30.0;
  std::string only_scheme;
  int only_stages = 0;
  bool landing_only = false;
  std::vector<int> element_counts = {1, 2, 4, 8};
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0) {
      json = true;
    } else if (std::strcmp(argv[i], "--budget") == 0 && i + 1 < argc) {
      budget = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--scheme") == 0 && i + 1 < argc &&
               (std::strcmp(argv[i + 1], "fesd") == 0 || std::strcmp(argv[i + 1], "fixed") == 0)) {
      only_scheme = argv[++i];
    } else if (std::strcmp(argv[i], "--stages") == 0 && i + 1 < argc && std::atoi(argv[i + 1]) >= 1 &&
               std::atoi(argv[i + 1]) <= 3) {
      only_stages = std::atoi(argv[++i]);
    } else if (std::strcmp(argv[i], "--refine") == 0 && i + 1 < argc && parse_number(argv[i + 1]) > 0.0 &&
               parse_number(argv[i + 1]) < 1e-9) {
      refinement = parse_number(argv[++i]);
    } else if (std::strcmp(argv[i], "--ipopt") == 0 && i + 1 < argc && parse_ipopt_option(argv[i + 1])) {
      ipopt_overrides.push_back(*parse_ipopt_option(argv[++i]));
    } else if (std::strcmp(argv[i], "--kappa") == 0 && i + 1 < argc && parse_number(argv[i + 1]) > 0.0 &&
               parse_number(argv[i + 1]) < 1.0) {
      kappa_override = parse_number(argv[++i]);
    } else if (std::strcmp(argv[i], "--sigma0") == 0 && i + 1 < argc && parse_number(argv[i + 1]) > 0.0) {
      sigma0_override = parse_number(argv[++i]);
    } else if (std::strcmp(argv[i], "--progress") == 0) {
      progress = true;
    } else if (std::strcmp(argv[i], "--landing-only") == 0) {
      landing_only = true;
    } else if (std::strcmp(argv[i], "--contact-side") == 0 && i + 1 < argc && parse_number(argv[i + 1]) >= 0.0) {
      contact_side = parse_number(argv[++i]);
    } else if (std::strcmp(argv[i], "--finite-elements") == 0 && i + 1 < argc) {
      element_counts.clear();
      for (const char* c = argv[++i]; *c;) {
        char* end = nullptr;
        const long n = std::strtol(c, &end, 10);
        if (end == c || n < 1 || n > 128) {
          std::fprintf(stderr, "--finite-elements: a comma-separated list of counts in [1, 128]\n");
          return 2;
        }
        element_counts.push_back(static_cast<int>(n));
        c = *end == ',' ? end + 1 : end;
      }
      if (element_counts.empty()) {
        std::fprintf(stderr, "--finite-elements: a comma-separated list of counts in [1, 128]\n");
        return 2;
      }
    } else {
      std::fprintf(stderr, "fesd_accuracy: \"%s\" is unknown, or its value is missing or out of range\n", argv[i]);
      std::fprintf(stderr,
                   "usage: %s [--json] [--budget SECONDS] [--scheme fesd|fixed] [--stages 1|2|3] "
                   "[--finite-elements N1,N2,...] [--refine TARGET] [--contact-side WEIGHT] [--landing-only] "
                   "[--ipopt NAME=VALUE]... [--kappa K] [--sigma0 S] [--progress]\n",
                   argv[0]);
      return 2;
    }
  }

  std::vector<Row> rows;
  std::vector<Dropped> dropped;
  std::vector<Order> orders;
  bool failed = false;
  for (const std::string scheme : {"fesd", "fixed"}) {
    if (landing_only || (!only_scheme.empty() && only_scheme != scheme)) continue;
    for (int ns = 1; ns <= 3; ++ns) {
      if (only_stages != 0 && ns != only_stages) continue;
      const std::size_t first = rows.size();
      std::string over_budget;  // the first configuration of this (scheme, n_s) above the budget
      for (std::size_t k = 0; k < element_counts.size(); ++k) {
        const int nfe = element_counts[k];
        if (k + 1 == element_counts.size() && !over_budget.empty()) {
          dropped.push_back({scheme, ns, nfe, over_budget});
          std::fprintf(stderr, "[%-5s n_s=%d N_fe=%d] dropped: %s\n", scheme.c_str(), ns, nfe, over_budget.c_str());
          break;
        }
        Row r;
        try {
          r = run_guiding(scheme, ns, nfe);
        } catch (const std::exception& e) {
          r.scheme = scheme_label(scheme);
          r.stages = ns;
          r.finite_elements = nfe;
          r.error = e.what();
          failed = true;
        }
        rows.push_back(r);
        if (r.error.empty())
          std::fprintf(stderr,
                       "[%-5s n_s=%d N_fe=%d] %3d elements, final err %s, touchdown %s, frozen end %s, lift-off %s%s, "
                       "%s, compl %s, %d iterations, %.1f s\n",
                       r.scheme.c_str(), ns, nfe, r.elements, cell(r.final_error).c_str(), cell(r.touchdown).c_str(),
                       cell(r.frozen_end).c_str(), r.lift_off_estimated ? "~" : "", cell(r.lift_off).c_str(),
                       r.converged ? "converged" : "NOT converged", cell(r.complementarity).c_str(), r.iterations,
                       r.seconds);
        else
          std::fprintf(stderr, "[%-5s n_s=%d N_fe=%d] threw: %s\n", r.scheme.c_str(), ns, nfe, r.error.c_str());
        if (r.error.empty() && r.seconds > budget && over_budget.empty()) {
          char reason[128];
          std::snprintf(reason, sizeof reason, "N_fe = %d took %.1f s > %.0f s", nfe, r.seconds, budget);
          over_budget = reason;
        }
      }
      // Observed orders between consecutive N_fe of this (scheme, n_s); h = 0.25 / N_fe.
      for (std::size_t i = first; i + 1 < rows.size(); ++i) {
        const Row& a = rows[i];
        const Row& b = rows[i + 1];
        Order o{a.scheme, ns, a.finite_elements, b.finite_elements, kNaN};
        if (a.final_error > 0.0 && b.final_error > 0.0)
          o.order = std::log(b.final_error / a.final_error) /
                    std::log(static_cast<double>(a.finite_elements) / b.finite_elements);
        orders.push_back(o);
      }
    }
  }
  Landing landing;
  const bool with_landing = landing_only || (only_scheme.empty() && only_stages == 0);
  if (with_landing) {
    try {
      landing = run_landing();
      std::fprintf(stderr, "[landing %s n_s=2 N_fe=5] stop err %s, %s, compl %s, %d iterations, %.1f s\n",
                   landing_label().c_str(), cell(landing.stop_error).c_str(), landing.converged ? "converged" : "NOT converged",
                   cell(landing.complementarity).c_str(), landing.iterations, landing.seconds);
    } catch (const std::exception& e) {
      landing.error = e.what();
      failed = true;
      std::fprintf(stderr, "[landing] threw: %s\n", landing.error.c_str());
    }
  }

  if (json) {
    auto guiding = nlohmann::ordered_json::array();
    for (const Row& r : rows) {
      nlohmann::ordered_json j = {{"scheme", r.scheme},
                                  {"n_s", r.stages},
                                  {"finite_elements", r.finite_elements},
                                  {"elements", r.elements},
                                  {"touchdown_time_error", number(r.touchdown)},
                                  {"frozen_end_error", number(r.frozen_end)},
                                  {"lift_off_error", number(r.lift_off)},
                                  {"lift_off_estimated", r.lift_off_estimated},
                                  {"final_state_error", number(r.final_error)},
                                  {"converged", r.converged},
                                  {"complementarity", number(r.complementarity)},
                                  {"ipopt_iterations", r.iterations},
                                  {"seconds", number(r.seconds)}};
      if (!r.error.empty()) j["error"] = r.error;
      guiding.push_back(std::move(j));
    }
    auto order_list = nlohmann::ordered_json::array();
    for (const Order& o : orders)
      order_list.push_back({{"scheme", o.scheme},
                            {"n_s", o.stages},
                            {"from_finite_elements", o.from},
                            {"to_finite_elements", o.to},
                            {"order", number(o.order)}});
    auto dropped_list = nlohmann::ordered_json::array();
    for (const Dropped& d : dropped)
      dropped_list.push_back(
          {{"scheme", d.scheme}, {"n_s", d.stages}, {"finite_elements", d.finite_elements}, {"reason", d.reason}});
    nlohmann::ordered_json land = {{"scheme", landing_label()},
                                   {"stop_error", number(landing.stop_error)},
                                   {"converged", landing.converged},
                                   {"complementarity", number(landing.complementarity)},
                                   {"ipopt_iterations", landing.iterations},
                                   {"seconds", number(landing.seconds)}};
    if (!landing.error.empty()) land["error"] = landing.error;
    const nlohmann::ordered_json out = {{"guiding_example", std::move(guiding)},
                                        {"orders", std::move(order_list)},
                                        {"dropped", std::move(dropped_list)},
                                        {"frictional_landing", with_landing ? land : nlohmann::ordered_json(nullptr)}};
    std::printf("%s\n", out.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace).c_str());
    return failed ? 1 : 0;
  }

  if (!landing_only) {
  std::printf("Guiding example (time-freezing paper, Example 3): 14 control intervals over tau in [0, 3.5]\n");
  std::printf("%-24s %4s %5s %9s %13s %14s %13s %11s %5s %9s %7s %9s\n", "scheme", "n_s", "N_fe", "elements",
              "touchdown err", "frozen-end err", "lift-off err", "final err", "conv", "compl", "iters", "seconds");
  for (const Row& r : rows) {
    if (!r.error.empty()) {
      std::printf("%-24s %4d %5d  threw: %s\n", r.scheme.c_str(), r.stages, r.finite_elements, r.error.c_str());
      continue;
    }
    const std::string lift = (r.lift_off_estimated ? "~" : "") + cell(r.lift_off);
    std::printf("%-24s %4d %5d %9d %13s %14s %13s %11s %5s %9s %7d %9.1f\n", r.scheme.c_str(), r.stages,
                r.finite_elements, r.elements, cell(r.touchdown).c_str(), cell(r.frozen_end).c_str(), lift.c_str(),
                cell(r.final_error).c_str(), r.converged ? "yes" : "NO", cell(r.complementarity).c_str(), r.iterations,
                r.seconds);
  }
  for (const Dropped& d : dropped)
    std::printf("dropped: %s n_s = %d N_fe = %d (%s)\n", d.scheme.c_str(), d.stages, d.finite_elements,
                d.reason.c_str());
  std::printf("\nObserved order of the final error, log(e2/e1) / log(h2/h1) (expected: fesd 2 n_s - 1, fixed 1)\n");
  std::printf("%-24s %4s %12s %8s\n", "scheme", "n_s", "N_fe", "order");
  for (const Order& o : orders) {
    char span[32];
    std::snprintf(span, sizeof span, "%d -> %d", o.from, o.to);
    std::printf("%-24s %4d %12s %8s\n", o.scheme.c_str(), o.stages, span,
                std::isfinite(o.order) ? std::to_string(o.order).substr(0, 5).c_str() : "-");
  }
  }
  if (!with_landing) return failed ? 1 : 0;
  std::printf("\nFrictional landing (g = 10, mu = 0.2, a_n = 20, 20 x 0.125, N_fe = 5, n_s = 2, %s)\n",
              landing_label().c_str());
  if (!landing.error.empty())
    std::printf("threw: %s\n", landing.error.c_str());
  else
    std::printf("stop err |x - 2.45| %s, converged %s, compl %s, %d Ipopt iterations, %.1f s\n",
                cell(landing.stop_error).c_str(), landing.converged ? "yes" : "NO",
                cell(landing.complementarity).c_str(), landing.iterations, landing.seconds);
  return failed ? 1 : 0;
}
