// Counts heap allocations while a CountAllocations guard is alive (allocation_counter.cpp; link
// that file and the -Wl,--wrap=malloc,calloc,realloc,posix_memalign options, see
// tests/CMakeLists.txt).
#pragma once

#include <atomic>

namespace saltus::testing {

extern std::atomic<bool> counting;
extern std::atomic<long> allocations;

struct CountAllocations {
  CountAllocations() {
    allocations = 0;
    counting = true;
  }
  ~CountAllocations() { counting = false; }
  CountAllocations(const CountAllocations&) = delete;
  CountAllocations& operator=(const CountAllocations&) = delete;
};

}  // namespace saltus::testing
