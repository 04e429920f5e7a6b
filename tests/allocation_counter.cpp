// The heap-allocation counter of the no-allocation tests (allocation_counter.hpp): every malloc,
// calloc, realloc and posix_memalign (the executable links with -Wl,--wrap=malloc,...: Eigen
// allocates through malloc from the code inlined into Saltus' objects) and every global operator
// new (replaced here) is counted while `counting` is set.
#include "allocation_counter.hpp"

#include <cstdlib>
#include <new>

namespace saltus::testing {
std::atomic<bool> counting{false};
std::atomic<long> allocations{0};
}  // namespace saltus::testing

namespace {
void count() {
  using saltus::testing::counting;
  using saltus::testing::allocations;
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
