// Human-readable summaries of a simulated trajectory and its report files: one line per event
// (time, guards that fired, mode before and after), a status line with the run's statistics,
// and the JSON + CSV files of trajectory_io.hpp written side by side. What the examples print;
// installed with the package so that a user's program prints the same.
#pragma once

#include <saltus/hybrid/vocabulary/trajectory_io.hpp>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace saltus {

/// The folder report files go to: $SALTUS_REPORT_DIR when set and not empty, else ./report;
/// created if missing. Throws std::filesystem::filesystem_error when it cannot be created.
inline std::filesystem::path report_directory() {
  const char* env = std::getenv("SALTUS_REPORT_DIR");
  std::filesystem::path dir = env && *env ? env : "report";
  std::filesystem::create_directories(dir);
  return dir;
}

/// Prints one line per event to `out`: "t = <s>  <contact> <guard kind>, ...  <mode before> ->
/// <mode after>" (contacts by their scene names, modes as describe() writes them; an impact without
/// collision, Transition::impact_without_collision, as "<contact> impact without collision"), then the
/// status, the number of events, the integrator's steps and right-hand-side evaluations and the
/// wall time; a trajectory no integrator produced (statistics all zero: e.g. one recovered from
/// a time-freezing solution, timefreezing/drivers/simulate.hpp) says so instead of "0 steps".
template <Scene S>
void print_events(const S& scene, const HybridTrajectory<S>& traj, std::FILE* out = stdout) {
  for (const auto& ev : traj.events) {
    std::string guards;
    for (const auto& tr : ev.transitions) {
      for (const Guard& g : tr.guards)
        guards += std::string(guards.empty() ? "" : ", ") + scene.contact(g.contact).name + " " + to_string(g.kind);
      if (!tr.impact_without_collision) continue;
      for (int i = 0; i < S::nc; ++i)
        if (tr.impulse_mode[i].role != ImpulseRole::None)
          guards += std::string(guards.empty() ? "" : ", ") + scene.contact(i).name + " impact without collision";
    }
    std::fprintf(out, "  t = %.12f  %-28s %s -> %s\n", ev.t, guards.c_str(), describe(scene, ev.mode_before).c_str(),
                 describe(scene, ev.mode_after).c_str());
  }
  const auto& st = traj.statistics;
  if (st.steps == 0 && st.rejected_steps == 0 && st.rhs_evaluations == 0 && st.wall_seconds == 0.0) {
    std::fprintf(out, "  status %s, %zu events, not integrated (no integrator statistics)\n", to_string(traj.status),
                 traj.events.size());
    return;
  }
  std::fprintf(out, "  status %s, %zu events, %ld steps, %ld rhs evaluations, %.3f ms\n", to_string(traj.status),
               traj.events.size(), st.steps, st.rhs_evaluations, 1e3 * st.wall_seconds);
}

/// Writes <directory>/<name>.json (write_json: segments and events) and <directory>/<name>.csv
/// (write_csv: samples every dt seconds, both sides of every event) and prints their paths to
/// `log` (stderr where stdout carries a report). Throws InvalidArgument when a file cannot be
/// opened for writing.
template <Scene S>
void write_trajectory_files(const S& scene, const HybridTrajectory<S>& traj, const std::string& name, double dt,
                            const std::filesystem::path& directory = report_directory(), std::FILE* log = stdout) {
  const auto json_path = directory / (name + ".json"), csv_path = directory / (name + ".csv");
  std::ofstream json(json_path);
  SALTUS_REQUIRE(json.good(), "cannot write ", json_path.string());
  write_json(json, traj, scene);
  std::ofstream csv(csv_path);
  SALTUS_REQUIRE(csv.good(), "cannot write ", csv_path.string());
  write_csv(csv, traj, dt, scene);
  std::fprintf(log, "  wrote %s and %s\n", json_path.c_str(), csv_path.c_str());
}

}  // namespace saltus
