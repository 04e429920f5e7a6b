// The report folder of each scene: what the example programs write for the main job
// (examples/demo.sh) and examples/plot_report.py reads. Under the report directory
// (report_directory(): $SALTUS_REPORT_DIR, else ./report) one folder per scene,
//   <report>/<scene>/trajectory.json   segments and events (write_json, trajectory_io.hpp)
//                    trajectory.csv    samples: t, segment, mode, q.., v.., u..  (write_csv)
//                    forces.csv        contact forces along it (write_contact_forces_csv)
//                    report.json       a pipeline's report (demo.sh redirects a program's --json
//                                      output there)
//                    jump_gains.json   the hopper hop's jump gains (hopper.cpp)
//                    *.png             the figures plot_report.py draws there
// and <report>/index.html, the page that shows them all. The folder names (docs/report.md):
// bouncing_ball, guiding_example, plank_box, hopper, spatial_box, tracking_stability, and the two
// flagship pipelines plank_box_flat_landing and hopper_over_three_holes.
#pragma once

#include <saltus/hybrid/dynamics/contact_forces_csv.hpp>
#include <saltus/hybrid/vocabulary/trajectory_report.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace saltus::examples {

/// report_directory() / scene, created if missing (std::filesystem::filesystem_error when it
/// cannot be).
inline std::filesystem::path scene_directory(const std::string& scene) {
  std::filesystem::path dir = report_directory() / scene;
  std::filesystem::create_directories(dir);
  return dir;
}

/// Writes <report>/<scene>/trajectory.json and trajectory.csv (samples every dt seconds, both
/// sides of every event; write_trajectory_files) and prints their paths to `log` (stderr where
/// stdout carries a report). Throws InvalidArgument when a file cannot be opened for writing.
template <Scene S>
void write_scene_trajectory(const S& scene, const HybridTrajectory<S>& traj, const std::string& folder, double dt,
                            std::FILE* log = stdout) {
  write_trajectory_files(scene, traj, "trajectory", dt, scene_directory(folder), log);
}

/// Writes <report>/<scene>/forces.csv (write_contact_forces_csv: t, segment, <contact>_n,
/// <contact>_t0.., sampled as the trajectory) and prints its path to `log`. Throws
/// InvalidArgument when the file cannot be opened for writing.
template <Scene S>
void write_scene_forces(const S& scene, const HybridTrajectory<S>& traj, const std::string& folder, double dt,
                        std::FILE* log = stdout) {
  const std::filesystem::path path = scene_directory(folder) / "forces.csv";
  std::ofstream csv(path);
  SALTUS_REQUIRE(csv.good(), "cannot write ", path.string());
  write_contact_forces_csv(csv, traj, dt, scene);
  std::fprintf(log, "  wrote %s\n", path.c_str());
}

}  // namespace saltus::examples
