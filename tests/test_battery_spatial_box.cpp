// The scene battery (scene_battery.hpp) on the spatial box scene.
#include "scene_battery.hpp"

namespace saltus::testing {
namespace {

INSTANTIATE_TYPED_TEST_SUITE_P(SpatialBox, SceneBattery, ::testing::Types<scenes::SpatialBox>);



}  // namespace
}  // namespace saltus::testing
