// The allocation counter itself (allocation_counter.hpp) sees Eigen's and C++'s allocations; the
// hot paths of every scene (flow, jump map, their derivatives, the impact) are checked in its
// battery (scene_battery.hpp, HotPathsAllocateNothing).
#include "allocation_counter.hpp"

#include <Eigen/Core>
#include <gtest/gtest.h>

#include <vector>

namespace saltus::testing {
namespace {

TEST(NoAllocation, TheCounterSeesEigenAndNewAllocations) {
  long eigen = 0, cpp = 0;
  {
    CountAllocations guard;
    Eigen::MatrixXd m = Eigen::MatrixXd::Random(7, 7);
    eigen = allocations;
    EXPECT_NE(m(3, 3), 2.0);
  }
  {
    CountAllocations guard;
    std::vector<double> v(100, 1.0);
    cpp = allocations;
    EXPECT_EQ(v[50], 1.0);
  }
  EXPECT_GE(eigen, 1);
  EXPECT_GE(cpp, 1);
}

}  // namespace
}  // namespace saltus::testing
