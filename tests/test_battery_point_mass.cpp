// The scene battery (scene_battery.hpp) on the point mass scene.
#include "scene_battery.hpp"

namespace saltus::testing {
namespace {

INSTANTIATE_TYPED_TEST_SUITE_P(PointMass, SceneBattery, ::testing::Types<scenes::PointMass>);



}  // namespace
}  // namespace saltus::testing
