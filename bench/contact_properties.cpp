// Contact properties of the impact solver on every scene of the factory (examples/scenes):
// over N random pre-impact states (scenes::random_pre_impact_state, fixed seed 12345, as in
// tests/test_impact.cpp), the worst Signorini and Coulomb residuals of the returned (v+, Lambda),
// the largest relative kinetic-energy change (KE+ - KE-)/KE-, how many impacts had a singular
// Delassus matrix, which solver answered (Lemke, or the semismooth Newton fallback / spatial
// friction), how often the minimum-norm impulse was returned, and the mean wall time of one
// ImpactSolver::solve call (steady_clock around one loop over the N pre-generated states).
//
//   contact_properties [--json] [--impacts N]
//
// --json writes exactly one JSON object on stdout (diagnostics go to stderr):
//   {"point_mass": {"impacts": N, "max_signorini_residual": r, "max_coulomb_residual": r,
//                   "max_energy_gain": e, "singular_cases": k, "impact_solve_us": t,
//                   "solver": {"lemke_fraction": f, "minimum_norm_fraction": f}}, ...}
// without it, a table with one row per scene. Exits 1 if any residual exceeds 1e-12, if a scene
// whose contacts all have e_n = 0 gains kinetic energy above 1e-12 (relative), or if a solve
// throws; the reason is printed on stderr.
#include "scenes/all_scenes.hpp"
#include "scenes/sampling.hpp"

#include <saltus/hybrid/dynamics/impact.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace {

constexpr double kResidualLimit = 1e-12;
constexpr double kEnergyGainLimit = 1e-12;

struct SceneRow {
  std::string name;
  int impacts = 0;
  double max_signorini = 0.0, max_coulomb = 0.0, max_energy_gain = -std::numeric_limits<double>::infinity();
  int singular = 0, lemke = 0, minimum_norm = 0, failures = 0;
  double solve_us = 0.0;
  bool inelastic = true;  ///< every contact has e_n = 0
  std::vector<std::string> problems;
};

/// What is kept of one ImpactResult inside the timed loop (the result is overwritten by the next
/// solve).
struct Record {
  double signorini, coulomb, energy_gain;
  bool singular, lemke, minimum_norm, failed;
};

template <class S>
SceneRow measure(const S& scene, int impacts) {
  constexpr int nx = 2 * S::nq;
  SceneRow row;
  row.name = S::name;
  row.impacts = impacts;
  for (int i = 0; i < S::nc; ++i) row.inelastic = row.inelastic && scene.contact(i).restitution == 0.0;

  std::mt19937 rng(12345);
  std::vector<saltus::Vec<nx>> states;
  states.reserve(static_cast<std::size_t>(impacts));
  for (int k = 0; k < impacts; ++k) states.push_back(saltus::scenes::random_pre_impact_state(scene, rng));

  std::vector<Record> records(static_cast<std::size_t>(impacts));
  std::string first_failure;
  saltus::ImpactSolver<S> solver(scene);
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < impacts; ++k) {
    try {
      const auto& r = solver.solve(states[k]);
      records[k] = Record{r.signorini_residual,
                          r.coulomb_residual,
                          (r.kinetic_energy_plus - r.kinetic_energy_minus) / r.kinetic_energy_minus,
                          r.singular_delassus,
                          r.used_lemke,
                          r.minimum_norm_impulse,
                          false};
    } catch (const std::exception& e) {
      records[k] = Record{0, 0, 0, false, false, false, true};
      if (first_failure.empty()) first_failure = "state " + std::to_string(k) + ": " + e.what();
    }
  }
  const auto stop = std::chrono::steady_clock::now();
  row.solve_us = std::chrono::duration<double, std::micro>(stop - start).count() / impacts;

  int worst_signorini = -1, worst_coulomb = -1, worst_gain = -1;
  for (int k = 0; k < impacts; ++k) {
    const Record& r = records[k];
    if (r.failed) {
      ++row.failures;
      continue;
    }
    // NaN counts as the worst value.
    if (worst_signorini < 0 || !(r.signorini <= row.max_signorini)) {
      row.max_signorini = r.signorini;
      worst_signorini = k;
    }
    if (worst_coulomb < 0 || !(r.coulomb <= row.max_coulomb)) {
      row.max_coulomb = r.coulomb;
      worst_coulomb = k;
    }
    if (worst_gain < 0 || !(r.energy_gain <= row.max_energy_gain)) {
      row.max_energy_gain = r.energy_gain;
      worst_gain = k;
    }
    row.singular += r.singular;
    row.lemke += r.lemke;
    row.minimum_norm += r.minimum_norm;
  }

  char buf[256];
  if (row.failures > 0)
    row.problems.push_back(std::to_string(row.failures) + " of " + std::to_string(impacts) +
                           " impact solves threw; first: " + first_failure);
  if (!(row.max_signorini <= kResidualLimit)) {
    std::snprintf(buf, sizeof buf, "Signorini residual %.3e > %.0e at state %d", row.max_signorini, kResidualLimit,
                  worst_signorini);
    row.problems.emplace_back(buf);
  }
  if (!(row.max_coulomb <= kResidualLimit)) {
    std::snprintf(buf, sizeof buf, "Coulomb residual %.3e > %.0e at state %d", row.max_coulomb, kResidualLimit,
                  worst_coulomb);
    row.problems.emplace_back(buf);
  }
  if (row.inelastic && !(row.max_energy_gain <= kEnergyGainLimit)) {
    std::snprintf(buf, sizeof buf, "kinetic energy gained with e_n = 0: (KE+ - KE-)/KE- = %.3e > %.0e at state %d",
                  row.max_energy_gain, kEnergyGainLimit, worst_gain);
    row.problems.emplace_back(buf);
  }
  return row;
}

/// A JSON number as printed with `format` (JSON has no NaN or infinity: those become null).
nlohmann::ordered_json number(double x, const char* format = "%.3e") {
  if (!std::isfinite(x)) return nullptr;
  char buf[64];
  std::snprintf(buf, sizeof buf, format, x);
  return std::strtod(buf, nullptr);
}

void write_json(const std::vector<SceneRow>& rows) {
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  for (const SceneRow& r : rows) {
    const double n = std::max(1, r.impacts);
    out[r.name] = {{"impacts", r.impacts},
                   {"max_signorini_residual", number(r.max_signorini)},
                   {"max_coulomb_residual", number(r.max_coulomb)},
                   {"max_energy_gain", number(r.max_energy_gain)},
                   {"singular_cases", r.singular},
                   {"impact_solve_us", number(r.solve_us)},
                   {"solver",
                    {{"lemke_fraction", number(r.lemke / n, "%.4f")},
                     {"minimum_norm_fraction", number(r.minimum_norm / n, "%.4f")}}}};
  }
  std::fputs((out.dump() + "\n").c_str(), stdout);
}

void write_table(const std::vector<SceneRow>& rows) {
  std::printf("%-14s %8s %14s %14s %14s %9s %8s %9s %10s\n", "scene", "impacts", "max Signorini", "max Coulomb",
              "max dKE/KE", "singular", "Lemke", "min-norm", "us/solve");
  for (const SceneRow& r : rows) {
    const double n = std::max(1, r.impacts);
    std::printf("%-14s %8d %14.3e %14.3e %14.3e %9d %7.1f%% %8.1f%% %10.2f\n", r.name.c_str(), r.impacts,
                r.max_signorini, r.max_coulomb, r.max_energy_gain, r.singular, 100.0 * r.lemke / n,
                100.0 * r.minimum_norm / n, r.solve_us);
  }
  std::printf("Residuals are relative (impact.hpp); dKE/KE = (KE+ - KE-)/KE-, negative means energy is lost.\n");
}

[[noreturn]] void usage(const char* argv0, int code) {
  std::fprintf(code ? stderr : stdout, "usage: %s [--json] [--impacts N]\n", argv0);
  std::exit(code);
}

}  // namespace

int main(int argc, char** argv) {
  bool json = false;
  int impacts = 10000;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--json") {
      json = true;
    } else if (arg == "--impacts" && a + 1 < argc) {
      char* end = nullptr;
      const long n = std::strtol(argv[++a], &end, 10);
      if (end == argv[a] || *end != '\0' || n < 1 || n > 100000000) {
        std::fprintf(stderr, "%s: --impacts needs a positive integer, got '%s'\n", argv[0], argv[a]);
        return 2;
      }
      impacts = static_cast<int>(n);
    } else if (arg == "--help" || arg == "-h") {
      usage(argv[0], 0);
    } else {
      usage(argv[0], 2);
    }
  }

  std::vector<SceneRow> rows;
  saltus::scenes::for_each_scene([&](const auto& scene) { rows.push_back(measure(scene, impacts)); });

  if (json)
    write_json(rows);
  else
    write_table(rows);

  bool ok = true;
  for (const SceneRow& r : rows)
    for (const std::string& p : r.problems) {
      std::fprintf(stderr, "contact_properties: %s: %s\n", r.name.c_str(), p.c_str());
      ok = false;
    }
  return ok ? 0 : 1;
}
