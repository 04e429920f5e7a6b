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
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
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

namespace {

/// Texts that differ only in the time " t = <number>" they name (the first one), counted as one
/// kind with the range of its times: "3 x events stall at t = 1.91 .. 1.93: ...". A text without
/// a time is its own kind.
class CountedByKind {
 public:
  void add(const std::string& text) {
    std::size_t at = text.find("t = ");
    while (at != std::string::npos && at > 0 && text[at - 1] != ' ' && text[at - 1] != '(') at = text.find("t = ", at + 1);
    char* end = nullptr;
    const double t = at == std::string::npos ? std::numeric_limits<double>::quiet_NaN()
                                              : std::strtod(text.c_str() + at + 4, &end);
    const bool timed = at != std::string::npos && end != text.c_str() + at + 4;
    const std::size_t number_end = timed ? static_cast<std::size_t>(end - text.c_str()) : text.size();
    Kind& kind = kinds_[timed ? std::make_pair(text.substr(0, at + 4), text.substr(number_end))
                              : std::make_pair(text, std::string())];
    kind.timed = timed;
    if (kind.count++ == 0) kind.first = kind.last = t;
    kind.first = std::min(kind.first, t);
    kind.last = std::max(kind.last, t);
  }
  /// "count x text", the time replaced by "first .. last" (10 significant digits) when they differ.
  std::vector<std::string> lines() const {
    std::vector<std::string> out;
    for (const auto& [key, kind] : kinds_) {
      std::ostringstream line;
      line.precision(10);
      line << kind.count << " x " << key.first;
      if (kind.timed) {
        line << kind.first;
        if (kind.last != kind.first) line << " .. " << kind.last;
      }
      line << key.second;
      out.push_back(line.str());
    }
    return out;
  }

 private:
  struct Kind {
    int count = 0;
    bool timed = false;
    double first = 0.0, last = 0.0;
  };
  std::map<std::pair<std::string, std::string>, Kind> kinds_;  // the text before and after the time
};

}  // namespace

void summarise_monte_carlo(MonteCarloReport& report, double horizon) {
  report.runs = static_cast<int>(report.run.size());
  report.failed = report.kept_event_sequence = report.grew = report.shrank = 0;
  report.failure_reasons.clear();
  report.departures.clear();
  report.max_log_discrepancy = 0.0;
  report.observed_rate_median = 0.0;
  CountedByKind reasons, departures;
  std::vector<double> rates;
  report.observed_rate_max = report.predicted_rate_max = -std::numeric_limits<double>::infinity();
  for (const MonteCarloRun& r : report.run) {
    if (r.failed) {
      ++report.failed;
      reasons.add(r.reason);
      continue;
    }
    if (!r.kept_event_sequence) {
      departures.add(r.departure);
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
  report.failure_reasons = reasons.lines();
  report.departures = departures.lines();
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
