// What the flagship-OCP benchmarks (hopper_ocp, plank_box_ocp) share: their command line and the
// second homotopy of the variants that change the relaxation on the way ("smoothing, then ...").
//
//   NAME [--json] [--only VARIANT] [--max-steps K] [--integrated-gap] [--velocity-cross]
//        [--gap-scale K] [--contact-side W]
//        [--element-length-freedom G] [--warm-start primal|primal-dual] [--kappa K]
//        [--polish-below S] [--polish-max-iter K] [--max-iter K] [--ipopt OPTION=VALUE]...
//
// --max-steps K overrides the homotopy's step budget; --integrated-gap solves every variant with the gap switching
// functions read from the integrated gaps (FesdOptions::switching.integrated_gap); --velocity-cross with
// cross-complementarity on the velocity switching functions too
// (FesdOptions::switching.velocity_detection); --gap-scale K sets the gaps' switching-function scale K_gap in (0, 1e6] [1/m]
// (FesdOptions::switching.scale[0]); --contact-side W sets the contact-side selection's weight
// rho_c in [0, 1e3] (FesdOptions::regularisation.contact_side; 0 switches it off) for every variant;
// --element-length-freedom G sets gamma_h in [0, 1] (FesdOptions::grid.element_length_freedom: every
// element length in [(1 - G) h0, (1 + G) h0]; the default 1 lets an element shrink to length 0);
// --kappa K sets the homotopy's decrease factor in (0, 1) (MpccSolverOptions::Homotopy::kappa);
// --warm-start says what every solve after the first
// (continuation stages, homotopy steps, retries, polishes) starts from (MpccSolverOptions::
// warm_start: the previous primal-dual solution, the default, or its x alone); --polish-below and
// --polish-max-iter set MpccSolverOptions::Polish::below and max_iter; --ipopt passes an
// Ipopt option to every solve (an integer or a number when VALUE parses as one, else a string),
// e.g. `--ipopt mumps_pivtol=1e-4 --ipopt print_timing_statistics=yes --ipopt output_file=ip.log
// --ipopt file_print_level=5`.
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hpp>
#include <saltus/timefreezing/mpcc/mpcc_solver.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace saltus::bench {

struct OcpBenchArgs {
  bool json = false;
  std::string only;   ///< one variant by name; empty: all
  int max_steps = -1; ///< > 0: MpccSolverOptions::Homotopy::max_steps
  double gap_scale = 0.0;  ///< > 0: FesdOptions::switching.scale[0] (K_gap) for every variant
  double contact_side = -1.0;  ///< >= 0: FesdOptions::regularisation.contact_side (rho_c) for every variant
  double element_length_freedom = -1.0;  ///< in [0, 1]: FesdOptions::grid.element_length_freedom (gamma_h)
  bool integrated_gap = false;  ///< FesdOptions::switching.integrated_gap for every variant
  bool velocity_cross = false;  ///< FesdOptions::switching.velocity_detection for every variant
  int warm_start = -1;  ///< 1 primal-dual, 0 primal only: MpccSolverOptions::warm_start; -1: the variant's
  double polish_below = -1.0;  ///< >= 0: MpccSolverOptions::Polish::below
  int polish_max_iter = -1;    ///< > 0: MpccSolverOptions::Polish::max_iter
  int max_iter = -1;           ///< > 0: MpccSolverOptions::IpoptSettings::max_iter (per homotopy step)
  double kappa = -1.0;         ///< in (0, 1): MpccSolverOptions::Homotopy::kappa
  std::vector<timefreezing::IpoptOption> ipopt_options;

  /// The command line's share of a variant's solver options: the step budget, kappa, the warm
  /// start, the polish and the Ipopt options.
  void apply(timefreezing::MpccSolverOptions& s) const {
    if (max_steps > 0) s.homotopy.max_steps = max_steps;
    if (polish_below >= 0.0) s.polish.below = polish_below;
    if (warm_start >= 0) s.warm_start = warm_start == 1;
    if (polish_max_iter > 0) s.polish.max_iter = polish_max_iter;
    if (max_iter > 0) s.ipopt.max_iter = max_iter;
    if (kappa > 0.0) s.homotopy.kappa = kappa;
    s.ipopt.options.insert(s.ipopt.options.end(), ipopt_options.begin(), ipopt_options.end());
  }
  /// The command line's share of a variant's grid options: the integrated gap, the velocities' switch detection, the gap scale, the contact-side weight, the
  /// element lengths' freedom.
  void apply(timefreezing::FesdOptions& grid) const {
    if (integrated_gap) grid.switching.integrated_gap = true;
    if (velocity_cross) grid.switching.velocity_detection = true;
    if (gap_scale > 0.0) grid.switching.scale[0] = gap_scale;
    if (contact_side >= 0.0) grid.regularisation.contact_side = contact_side;
    if (element_length_freedom >= 0.0) grid.grid.element_length_freedom = element_length_freedom;
  }
};

/// "NAME=VALUE" as an Ipopt option: an integer or a number when VALUE parses as one, else a
/// string; nullopt when there is no name or no value.
inline std::optional<timefreezing::IpoptOption> parse_ipopt_option(const std::string& arg) {
  const std::size_t eq = arg.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == arg.size()) return std::nullopt;
  const std::string name = arg.substr(0, eq), value = arg.substr(eq + 1);
  char* end = nullptr;
  const long as_int = std::strtol(value.c_str(), &end, 10);
  if (*end == '\0') return timefreezing::IpoptOption{name, static_cast<int>(as_int)};
  const double as_double = std::strtod(value.c_str(), &end);
  if (*end == '\0') return timefreezing::IpoptOption{name, as_double};
  return timefreezing::IpoptOption{name, value};
}

/// A program's own switch (`--one-hole`, `--short`) taken out of the command line: sets `present`
/// and returns the other arguments (argv[0] first) for parse_ocp_bench_args.
inline std::vector<char*> take_own_flag(int argc, char** argv, const char* flag, bool& present) {
  present = false;
  std::vector<char*> rest{argv[0]};
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], flag) == 0) present = true;
    else rest.push_back(argv[i]);
  }
  return rest;
}

/// The parsed command line, or nullopt after printing the usage line (bad or unknown argument).
inline std::optional<OcpBenchArgs> parse_ocp_bench_args(int argc, char** argv, const char* program) {
  OcpBenchArgs a;
  // An integer argument in [lo, hi], the whole string parsed; false (out left as it is) otherwise.
  const auto integer_in = [](const char* text, long lo, long hi, int& out) {
    char* end = nullptr;
    const long k = std::strtol(text, &end, 10);
    if (end == text || *end != '\0' || k < lo || k > hi) return false;
    out = static_cast<int>(k);
    return true;
  };
  // A whole-string number for which valid(value) holds (NaN fails every range test).
  const auto number_in = [](const char* text, auto valid, double& out) {
    char* end = nullptr;
    const double v = std::strtod(text, &end);
    if (end == text || *end != '\0' || !valid(v)) return false;
    out = v;
    return true;
  };
  const auto usage = [program] {
    std::fprintf(stderr,
                 "usage: %s [--json] [--only NAME] [--max-steps K] [--integrated-gap] [--velocity-cross] "
                 "[--gap-scale K] [--contact-side W] [--element-length-freedom G] [--warm-start primal|primal-dual] [--kappa K] [--polish-below S] [--polish-max-iter K] [--max-iter K] [--ipopt NAME=VALUE]...\n"
                 "  (NAME non-empty; --max-steps 1..1000; --max-iter, --polish-max-iter 1..100000; --gap-scale in (0, 1e6];\n"
                 "   --contact-side in [0, 1e3]; --element-length-freedom in [0, 1]; --kappa in (0, 1); --warm-start default primal-dual; --polish-below in [0, 1])\n",
                 program);
    return std::optional<OcpBenchArgs>();
  };
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0) a.json = true;
    else if (std::strcmp(argv[i], "--only") == 0 && i + 1 < argc) {
      a.only = argv[++i];
      if (a.only.empty()) return usage();  // an empty name would run every variant
    }
    else if (std::strcmp(argv[i], "--integrated-gap") == 0) a.integrated_gap = true;
    else if (std::strcmp(argv[i], "--velocity-cross") == 0) a.velocity_cross = true;
    else if (std::strcmp(argv[i], "--max-steps") == 0 && i + 1 < argc) {
      if (!integer_in(argv[++i], 1, 1000, a.max_steps)) return usage();
    } else if (std::strcmp(argv[i], "--polish-below") == 0 && i + 1 < argc) {
      if (!number_in(argv[++i], [](double s) { return s >= 0.0 && s <= 1.0; }, a.polish_below)) return usage();
    } else if (std::strcmp(argv[i], "--gap-scale") == 0 && i + 1 < argc) {
      if (!number_in(argv[++i], [](double k) { return k > 0.0 && k <= 1e6; }, a.gap_scale)) return usage();
    } else if (std::strcmp(argv[i], "--contact-side") == 0 && i + 1 < argc) {
      if (!number_in(argv[++i], [](double w) { return w >= 0.0 && w <= 1e3; }, a.contact_side)) return usage();
    } else if (std::strcmp(argv[i], "--element-length-freedom") == 0 && i + 1 < argc) {
      if (!number_in(argv[++i], [](double g) { return g >= 0.0 && g <= 1.0; }, a.element_length_freedom)) return usage();
    } else if (std::strcmp(argv[i], "--kappa") == 0 && i + 1 < argc) {
      if (!number_in(argv[++i], [](double k) { return k > 0.0 && k < 1.0; }, a.kappa)) return usage();
    } else if (std::strcmp(argv[i], "--warm-start") == 0 && i + 1 < argc) {
      const std::string kind = argv[++i];
      if (kind == "primal") a.warm_start = 0;
      else if (kind == "primal-dual") a.warm_start = 1;
      else return usage();
    } else if (std::strcmp(argv[i], "--polish-max-iter") == 0 && i + 1 < argc) {
      if (!integer_in(argv[++i], 1, 100000, a.polish_max_iter)) return usage();
    } else if (std::strcmp(argv[i], "--max-iter") == 0 && i + 1 < argc) {
      if (!integer_in(argv[++i], 1, 100000, a.max_iter)) return usage();
    } else if (std::strcmp(argv[i], "--ipopt") == 0 && i + 1 < argc) {
      std::optional<timefreezing::IpoptOption> option = parse_ipopt_option(argv[++i]);
      if (!option) return usage();
      a.ipopt_options.push_back(std::move(*option));
    } else
      return usage();
  }
  return a;
}

/// Whether `only` (the --only NAME argument; empty: every variant) names one of `variants` (each
/// with a `name`); if not, prints "<program>: no variant named ..." with the names to stderr, so
/// that a mistyped name is an error (exit status 2), not an empty run.
template <class Variants>
bool only_names_a_variant(const std::string& only, const Variants& variants, const char* program) {
  if (only.empty()) return true;
  std::string names;
  for (const auto& v : variants) {
    if (only == v.name) return true;
    names += std::string(names.empty() ? "" : ", ") + v.name;
  }
  std::fprintf(stderr, "%s: no variant named '%s'; the variants: %s\n", program, only.c_str(), names.c_str());
  return false;
}

/// A second homotopy (`relaxation` from sigma_0, `steps` steps, polish on) from the primal-dual
/// solution `first` of an earlier homotopy on a problem with the same variables and rows; returns
/// its solution with `first`'s steps, iterations and seconds put in front.
inline timefreezing::MpccSolution continue_homotopy(const timefreezing::Mpcc& problem,
                                                    const timefreezing::MpccSolution& first,
                                                    timefreezing::MpccSolverOptions options,
                                                    timefreezing::MpccSolverOptions::Relaxation relaxation,
                                                    double sigma_0, int steps) {
  const timefreezing::MpccStart from{first.x, first.constraint_multipliers, first.bound_multipliers_lower,
                                     first.bound_multipliers_upper};
  options.homotopy.relaxation = relaxation;
  options.homotopy.sigma_0 = sigma_0;
  options.homotopy.max_steps = std::max(1, steps);
  options.polish.enabled = true;
  timefreezing::MpccSolution p = timefreezing::solve_mpcc(problem, from, options);
  p.steps.insert(p.steps.begin(), first.steps.begin(), first.steps.end());
  p.ipopt_iterations += first.ipopt_iterations;
  p.seconds += first.seconds;
  return p;
}

}  // namespace saltus::bench
