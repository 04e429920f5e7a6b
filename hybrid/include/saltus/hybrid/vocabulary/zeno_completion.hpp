// The record of an accumulation of impacts that the simulator continued past (Zeno completion,
// SimulationOptions::zeno_completion; the construction: simulation/zeno_completion.hpp).
#pragma once

#include <vector>

namespace saltus {

struct ZenoCompletion {
  /// s: the accumulation time the motion was continued from (the extrapolated limit of the
  /// touchdown times, HybridTrajectory::zeno_time at the detection).
  double t = 0.0;
  /// s: how far t may be from the accumulation time (HybridTrajectory::zeno_time_uncertainty at
  /// the detection, the extrapolation's and the integration's parts; infinite when t is the
  /// geometric estimate). The touchdowns after the completion carry it into a later accumulation.
  double uncertainty = 0.0;
  /// s: the last touchdown resolved before the accumulation; the motion between it and t (the
  /// unresolved tail of the accumulation) is recorded as the constant state after that touchdown.
  double last_touchdown = 0.0;
  /// The accumulating contacts (scene indices, ascending): those that touched down within the
  /// detection window; closed in the limit state.
  std::vector<int> contacts;
  /// The index of the completion's event in HybridTrajectory::events.
  int event = -1;
};

}  // namespace saltus
