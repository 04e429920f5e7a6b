// The scene factory: every example scene with its default parameters. Tests run one battery
// over `AllScenes` (derivatives, invariants, bad input); `all()` gives one instance of each.
#pragma once

#include "scenes/bouncing_ball.hpp"
#include "scenes/hopper.hpp"
#include "scenes/plank_box.hpp"
#include "scenes/point_mass.hpp"
#include "scenes/spatial_box.hpp"

#include <tuple>

namespace saltus::scenes {

using AllScenes = std::tuple<PointMass, BouncingBall, PlankBox, Hopper, SpatialBox>;

/// One default-constructed instance of every scene.
inline AllScenes all() { return AllScenes{}; }

/// Calls f(scene) for every scene of all().
template <class F>
void for_each_scene(F&& f) {
  std::apply([&](const auto&... scene) { (f(scene), ...); }, all());
}

}  // namespace saltus::scenes
