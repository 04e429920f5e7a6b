// Shared by the flagship suites: the event structure of a hopper reference over the one-hole bed
// (scenes::HopperOverOneHole), checked as a structure that any gait over the hole passes.
#pragma once

#include "scenes/hopper_holes.hpp"

#include <saltus/hybrid/vocabulary/trajectory.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace saltus::testing {

/// The events of a one-hole reference, one line each (time, impact, foot x [m] before the event,
/// the guards), for failure messages.
inline std::string list_one_hole_events(const std::vector<Event<scenes::Hopper>>& events) {
  const scenes::HopperOverOneHole ocp;
  std::ostringstream listed;
  for (const auto& ev : events) {
    listed << "\n  t = " << ev.t << (ev.impact() ? " impact" : "") << " foot x "
           << ocp.path_constraints<double>(ev.x_minus, Vec<2>::Zero())[1];  // path row 1: foot x
    for (const Guard& g : ev.guards()) listed << " " << to_string(g.kind);
  }
  return listed.str();
}

/// Checks that every event has one guard, every touchdown lands on the ground outside the hole's
/// ellipse (|foot x - 0.5| >= 0.25 m, to 1e-6), exactly one flight goes from before the hole's near
/// edge to beyond its far edge, and no lift-off comes last (the fixed target puts the foot on the
/// ground). Non-fatal failures (EXPECT), each with the event list.
inline void expect_one_hole_event_structure(const std::vector<Event<scenes::Hopper>>& events) {
  using Short = scenes::HopperOverOneHole;
  const Short ocp;
  const std::string listed = list_one_hole_events(events);
  if (events.size() < 2) {
    ADD_FAILURE() << "fewer than two events:" << listed;
    return;
  }
  const double near_edge = Short::hole_centres[0] - Short::hole_half_width;  // 0.25 m
  const double far_edge = Short::hole_centres[0] + Short::hole_half_width;   // 0.75 m
  double last_lift_off_x = std::numeric_limits<double>::quiet_NaN();
  int crossings = 0;
  for (const auto& ev : events) {
    if (ev.guards().size() != 1) {
      ADD_FAILURE() << "an event with " << ev.guards().size() << " guards at t = " << ev.t << ":" << listed;
      return;
    }
    const double fx = ocp.path_constraints<double>(ev.x_minus, Vec<2>::Zero())[1];
    if (ev.guards()[0].kind == GuardKind::Release) last_lift_off_x = fx;
    if (ev.guards()[0].kind != GuardKind::Touchdown) continue;
    EXPECT_GE(std::abs(fx - Short::hole_centres[0]), Short::hole_half_width - 1e-6) << listed;
    if (last_lift_off_x <= near_edge + 1e-6 && fx >= far_edge - 1e-6) ++crossings;
  }
  EXPECT_EQ(crossings, 1) << "flights from before the hole to beyond it:" << listed;
  EXPECT_NE(events.back().guards()[0].kind, GuardKind::Release) << listed;
}

}  // namespace saltus::testing
