// The scene battery (scene_battery.hpp) on the hopper scene.
#include "scene_battery.hpp"

namespace saltus::testing {
namespace {

INSTANTIATE_TYPED_TEST_SUITE_P(Hopper, SceneBattery, ::testing::Types<scenes::Hopper>);

TEST(Hopper, MassMatrixMatchesTheKineticEnergyOfItsBodies) {
  scenes::Hopper hopper;
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec<4> q = random_vector<4>(rng, 1.5), v = random_vector<4>(rng, 3.0);
    const double from_m = 0.5 * v.dot(hopper.mass_matrix<double>(q) * v);
    EXPECT_NEAR(from_m, hopper.kinetic_energy_from_bodies<double>(q, v), 1e-12 * (1 + from_m));
  }
  // Standing straight on the ground at the start of the three-holes task: the foot touches.
  EXPECT_NEAR(hopper.gap<double>(0, Vec<4>(0, 0.4, 0, 0)), 0.0, 1e-15);
}

}  // namespace
}  // namespace saltus::testing
