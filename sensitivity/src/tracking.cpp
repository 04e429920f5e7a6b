// The scene-free part of tracking.hpp: verdict names and the thread pool of the Monte Carlo batch.
#include <saltus/sensitivity/tracking.hpp>

#include <atomic>
#include <exception>
#include <mutex>
#include <thread>

namespace saltus {

const char* to_string(StabilityVerdict v) {
  switch (v) {
    case StabilityVerdict::Stable: return "stable";
    case StabilityVerdict::Unstable: return "unstable";
    case StabilityVerdict::Undecided: return "undecided";
  }
  return "?";
}

namespace detail {

void parallel_for(int count, int threads, int batch, const std::function<void(int, int)>& body,
                  const std::function<void(int)>& after_batch) {
  SALTUS_REQUIRE(count >= 0 && threads >= 1 && batch >= 1, "parallel_for: count ", count, ", threads ", threads,
                 ", batch ", batch);
  std::atomic<int> next{0};
  std::mutex lock;
  int done = 0;
  std::exception_ptr first_error;
  auto worker = [&](int id) {
    for (int i = next.fetch_add(1); i < count; i = next.fetch_add(1)) {
      try {
        body(i, id);
      } catch (...) {
        const std::lock_guard<std::mutex> guard(lock);
        if (!first_error) first_error = std::current_exception();
      }
      const std::lock_guard<std::mutex> guard(lock);
      ++done;
      if (after_batch && (done % batch == 0 || done == count)) after_batch(done);
    }
  };
  std::vector<std::thread> pool;
  for (int w = 1; w < threads; ++w) pool.emplace_back(worker, w);
  worker(0);  // the calling thread is worker 0
  for (auto& t : pool) t.join();
  if (first_error) std::rethrow_exception(first_error);
}

}  // namespace detail
}  // namespace saltus
