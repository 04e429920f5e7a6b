// The scene battery (scene_battery.hpp) on the plank box scene.
#include "scene_battery.hpp"

namespace saltus::testing {
namespace {

INSTANTIATE_TYPED_TEST_SUITE_P(PlankBox, SceneBattery, ::testing::Types<scenes::PlankBox>);

TEST(PlankBox, EmptyPlankRestsHorizontally) {
  scenes::PlankBox plank_box;
  const Vec<4> q(0.5, 1.0, 0.0, 0.0);
  EXPECT_NEAR(plank_box.bias<double>(q, Vec<4>::Zero())[3], 0.0, 1e-12);
  // Flat box at rest on the plank: both corners touch at once.
  const Vec<4> flat = plank_box.flat_state(0.6, 0.0).head<4>();
  EXPECT_NEAR(plank_box.gap<double>(0, flat), 0.0, 1e-15);
  EXPECT_NEAR(plank_box.gap<double>(1, flat), 0.0, 1e-15);
}

}  // namespace
}  // namespace saltus::testing
