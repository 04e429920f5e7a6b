// Forwarding header, kept for one release (0.2): the data types moved to vocabulary/, their CSV
// and JSON reading and writing to vocabulary/trajectory_io.hpp (free functions now:
// write_csv(os, traj, dt, scene), write_json(os, traj, scene)). Include those instead.
#pragma once
#include <saltus/hybrid/vocabulary/trajectory.hpp>
#include <saltus/hybrid/vocabulary/trajectory_io.hpp>
