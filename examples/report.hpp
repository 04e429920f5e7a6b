// What every example program prints and writes: a one-line summary per event and the trajectory
// files under report/ (JSON: segments and events; CSV: samples of t, mode, x, u).
#pragma once

#include <saltus/hybrid/vocabulary/trajectory_io.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace saltus::examples {

/// The folder reports go to: $SALTUS_REPORT_DIR, or ./report.
inline std::filesystem::path report_dir() {
  const char* env = std::getenv("SALTUS_REPORT_DIR");
  std::filesystem::path dir = env && *env ? env : "report";
  std::filesystem::create_directories(dir);
  return dir;
}

template <Scene S>
void print_events(const S& scene, const HybridTrajectory<S>& traj) {
  for (const auto& ev : traj.events) {
    std::string guards;
    for (const Guard& g : ev.guards())
      guards += std::string(guards.empty() ? "" : ", ") + scene.contact(g.contact).name + " " + to_string(g.kind);
    std::printf("  t = %.12f  %-28s %s -> %s\n", ev.t, guards.c_str(), describe(scene, ev.mode_before).c_str(),
                describe(scene, ev.mode_after).c_str());
  }
  std::printf("  status %s, %zu events, %ld steps, %ld rhs evaluations, %.3f ms\n", to_string(traj.status),
              traj.events.size(), traj.statistics.steps, traj.statistics.rhs_evaluations,
              1e3 * traj.statistics.wall_seconds);
}

/// Writes report/<name>.json and report/<name>.csv (samples every dt).
template <Scene S>
void write_trajectory(const S& scene, const HybridTrajectory<S>& traj, const std::string& name, double dt) {
  const auto dir = report_dir();
  std::ofstream json(dir / (name + ".json"));
  saltus::write_json(json, traj, scene);
  std::ofstream csv(dir / (name + ".csv"));
  saltus::write_csv(csv, traj, dt, scene);
  std::printf("  wrote %s and %s\n", (dir / (name + ".json")).c_str(), (dir / (name + ".csv")).c_str());
}

}  // namespace saltus::examples
