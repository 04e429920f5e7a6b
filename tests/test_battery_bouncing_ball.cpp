// The scene battery (scene_battery.hpp) on the bouncing ball scene.
#include "scene_battery.hpp"

namespace saltus::testing {
namespace {

INSTANTIATE_TYPED_TEST_SUITE_P(BouncingBall, SceneBattery, ::testing::Types<scenes::BouncingBall>);



}  // namespace
}  // namespace saltus::testing
