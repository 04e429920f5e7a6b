// The contact forces along a trajectory as CSV, sampled as write_csv samples the state
// (vocabulary/trajectory_io.hpp): what a report plots beside the motion. The forces are the flow's
// (flow.hpp): in each segment's mode, from the Delassus system at the sampled state and input, so a
// closed contact's force is the one that holds it at the acceleration level and an open contact's
// is zero. The impulses of the impacts are in the events of to_json (trajectory_io.hpp).
#pragma once

#include <saltus/hybrid/dynamics/flow.hpp>
#include <saltus/hybrid/vocabulary/trajectory_io.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <string>

namespace saltus {

/// Writes one row per sample: t [s], segment, then per contact i (scene order) its normal force
/// `<name>_n` [N] and its tangential components `<name>_t0`, `<name>_t1` [N] (as many as the
/// contact has tangents, in its tangent coordinates). The samples are write_csv's: per segment
/// ceil((t_end - t_begin) / dt) intervals (at least one) and both end points, so both sides of
/// every event appear. dt > 0 [s]. Throws InvalidArgument for dt <= 0 or not finite, and what
/// evaluate_flow throws (NonSpdMassMatrix). Leaves the stream's precision at 17.
template <Scene S>
void write_contact_forces_csv(std::ostream& os, const HybridTrajectory<S>& traj, double dt, const S& scene) {
  SALTUS_REQUIRE(std::isfinite(dt) && dt > 0.0, "write_contact_forces_csv: dt must be finite and > 0, got ", dt);
  os << std::setprecision(17) << "t,segment";
  for (int i = 0; i < S::nc; ++i) {
    os << "," << scene.contact(i).name << "_n";
    for (int k = 0; k < scene.contact(i).tangents(); ++k) os << "," << scene.contact(i).name << "_t" << k;
  }
  os << "\n";
  FlowWorkspace<S> ws;
  for_each_sample(traj, dt, [&](int s, double t) {
    const Mode<S::nc>& mode = traj.segments[s].mode;
    evaluate_flow(scene, mode, traj.state(s, t), traj.input_at(s, t), ws);
    os << t << "," << s;
    for (int i = 0; i < S::nc; ++i) {
      const bool closed = mode[i].closed();
      os << "," << (closed ? ws.force[i].normal : 0.0);
      for (int j = 0; j < scene.contact(i).tangents(); ++j) os << "," << (closed ? ws.force[i].tangent[j] : 0.0);
    }
    os << "\n";
  });
}

/// Writes <directory>/<name>_forces.csv (write_contact_forces_csv) and prints its path to `log`.
/// Throws InvalidArgument when the file cannot be opened for writing, and as
/// write_contact_forces_csv.
template <Scene S>
void write_contact_forces_file(const S& scene, const HybridTrajectory<S>& traj, const std::string& name, double dt,
                               const std::filesystem::path& directory, std::FILE* log = stdout) {
  const auto path = directory / (name + "_forces.csv");
  std::ofstream csv(path);
  SALTUS_REQUIRE(csv.good(), "cannot write ", path.string());
  write_contact_forces_csv(csv, traj, dt, scene);
  std::fprintf(log, "  wrote %s\n", path.c_str());
}

}  // namespace saltus
