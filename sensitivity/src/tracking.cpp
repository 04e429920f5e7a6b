// The scene-free part of tracking.hpp: verdict names, the Monte Carlo summary and the thread pool of
// the Monte Carlo batch.
#include <saltus/sensitivity/tracking.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

namespace saltus {

const char* to_string(StabilityVerdict v) {
  switch (v) {
    case StabilityVerdict::Stable: return "stable";
    case StabilityVerdict::Unstable: return "unstable";
    case StabilityVerdict::Undecided: return "undecided";
  }
  return "?";
}

void summarise_monte_carlo(MonteCarloReport& report, double horizon) {
  report.runs = static_cast<int>(report.run.size());
  report.failed = report.kept_event_sequence = report.grew = report.shrank = 0;
  report.failure_reasons.clear();
  report.departures.clear();
  report.max_log_discrepancy = 0.0;
  report.observed_rate_median = 0.0;
  std::map<std::string, int> reasons;
  std::map<std::string, std::tuple<int, double, double>> departures;  // count, first and last time
  std::vector<double> rates;
  report.observed_rate_max = report.predicted_rate_max = -std::numeric_limits<double>::infinity();
  for (const MonteCarloRun& r : report.run) {
    if (r.failed) {
      ++report.failed;
      ++reasons[r.reason];
      continue;
    }
    if (!r.kept_event_sequence) {
      // Distinct up to the time "(t = ... s)" at the end of the text.
      const std::size_t at = r.departure.rfind(" (t = ");
      auto& [count, first, last] = departures[r.departure.substr(0, at)];
      const double t = at == std::string::npos ? std::numeric_limits<double>::quiet_NaN()
                                                : std::strtod(r.departure.c_str() + at + 6, nullptr);
      if (count++ == 0) first = last = t;
      first = std::min(first, t);
      last = std::max(last, t);
      continue;
    }
    ++report.kept_event_sequence;
    const double rate = std::log(r.observed) / horizon;
    rates.push_back(rate);
    report.observed_rate_max = std::max(report.observed_rate_max, rate);
    if (std::isfinite(r.predicted)) {
      report.predicted_rate_max = std::max(report.predicted_rate_max, std::log(r.predicted) / horizon);
      report.max_log_discrepancy = std::max(report.max_log_discrepancy, std::abs(std::log(r.observed / r.predicted)));
    }
    (r.observed > 1 ? report.grew : report.shrank) += 1;
  }
  if (!rates.empty()) {
    std::nth_element(rates.begin(), rates.begin() + static_cast<std::ptrdiff_t>(rates.size() / 2), rates.end());
    report.observed_rate_median = rates[rates.size() / 2];
  }
  if (rates.empty())  // no kept run: no statistic of them, rather than a 0 that reads as a result
    report.observed_rate_max = report.observed_rate_median = report.max_log_discrepancy =
        std::numeric_limits<double>::quiet_NaN();
  if (!std::isfinite(report.predicted_rate_max)) report.predicted_rate_max = std::numeric_limits<double>::quiet_NaN();
  for (const auto& [reason, count] : reasons) report.failure_reasons.push_back(detail::concat(count, " x ", reason));
  for (const auto& [departure, seen] : departures) {
    const auto& [count, first, last] = seen;
    report.departures.push_back(std::isnan(first) ? detail::concat(count, " x ", departure)
                                : first == last   ? detail::concat(count, " x ", departure, " (t = ", first, " s)")
                                                  : detail::concat(count, " x ", departure, " (t = ", first, " .. ", last, " s)"));
  }
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
