// Hot paths allocate nothing: the flow of every mode, the jump maps, their derivatives and the
// impact solve run with every heap allocation counted. Eigen allocates through malloc from the
// code inlined into Saltus' objects (this test links with -Wl,--wrap=malloc,...); C++ allocations
// go through the global operator new, replaced here. Both counters must stay at zero.
#include "scenes/sampling.hpp"
#include "support.hpp"

#include <saltus/hybrid/dynamics/derivatives.hpp>
#include <saltus/hybrid/dynamics/impact.hpp>

#include <atomic>
#include <cstdlib>
#include <new>

namespace {
std::atomic<bool> counting{false};
std::atomic<long> allocations{0};
void count() {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

extern "C" {
void* __real_malloc(std::size_t);
void* __real_calloc(std::size_t, std::size_t);
void* __real_realloc(void*, std::size_t);
int __real_posix_memalign(void**, std::size_t, std::size_t);
void* __wrap_malloc(std::size_t n) {
  count();
  return __real_malloc(n);
}
void* __wrap_calloc(std::size_t n, std::size_t s) {
  count();
  return __real_calloc(n, s);
}
void* __wrap_realloc(void* p, std::size_t n) {
  count();
  return __real_realloc(p, n);
}
int __wrap_posix_memalign(void** p, std::size_t a, std::size_t n) {
  count();
  return __real_posix_memalign(p, a, n);
}
}

// The replaced operator new takes memory from malloc, so operator delete gives it back with free.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t n) {
  count();
  if (void* p = __real_malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace saltus::testing {
namespace {

struct CountAllocations {
  CountAllocations() {
    allocations = 0;
    counting = true;
  }
  ~CountAllocations() { counting = false; }
};

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

template <class S>
class NoAllocation : public ::testing::Test {};
using Scenes = ::testing::Types<scenes::PointMass, scenes::BouncingBall, scenes::PlankBox, scenes::Hopper,
                                scenes::SpatialBox>;
TYPED_TEST_SUITE(NoAllocation, Scenes);

TYPED_TEST(NoAllocation, FlowJumpMapDerivativesAndImpact) {
  using S = TypeParam;
  constexpr int nx = 2 * S::nq, nu = S::nu;
  const S scene{};
  std::mt19937 rng(5);
  // Everything is made before counting starts.
  FlowWorkspace<S> flow_ws;
  JumpWorkspace<S> jump_ws;
  auto derivative_ws = std::make_unique<DerivativeWorkspace<S>>();
  auto impact = std::make_unique<ImpactSolver<S>>(scene);
  std::vector<Mode<S::nc>> modes;
  std::vector<Vec<nx>> states, pre_impact;
  for (int k = 0; k < 20; ++k) {
    modes.push_back(random_mode(scene, rng));
    states.push_back(consistent_with_mode(scene, modes.back(),
                                          stack(generic_configuration(scene, rng), random_vector<S::nq>(rng, 1.0))));
    pre_impact.push_back(scenes::random_pre_impact_state(scene, rng));
  }
  const Vec<nu> u = random_vector<nu>(rng, 1.0);
  Vec<nx> f, xp;
  Mat<nx, nx> A, G;
  Mat<nx, nu> B;
  long counted = 0;
  {
    CountAllocations guard;
    std::array<long, 6> by_step{};
    for (std::size_t k = 0; k < modes.size(); ++k) {
      long before = allocations;
      evaluate_flow(scene, modes[k], states[k], u, flow_ws);
      for (const Guard& g : active_guards(scene, modes[k])) (void)guard_value(scene, modes[k], g, flow_ws);
      by_step[0] += allocations - before;
      before = allocations;
      flow_jacobian(scene, modes[k], states[k], u, *derivative_ws, f, A, B);
      by_step[1] += allocations - before;
      before = allocations;
      const auto& r = impact->solve(pre_impact[k]);
      by_step[2] += allocations - before;
      before = allocations;
      apply_jump_map(scene, r.impulse_mode, pre_impact[k], jump_ws, xp);
      by_step[3] += allocations - before;
      before = allocations;
      jump_map_jacobian(scene, r.impulse_mode, pre_impact[k], *derivative_ws, xp, G);
      by_step[4] += allocations - before;
    }
    counted = allocations;
    counting = false;
    if (counted != 0)
      std::printf("allocations: flow %ld, flow Jacobian %ld, impact %ld, jump map %ld, jump Jacobian %ld\n", by_step[0],
                  by_step[1], by_step[2], by_step[3], by_step[4]);
  }
  EXPECT_EQ(counted, 0) << S::name << ": heap allocations in flows, jump maps, derivatives or impacts";
}

}  // namespace
}  // namespace saltus::testing
