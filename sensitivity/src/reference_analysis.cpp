// The scene-free part of analysis/reference_analysis.hpp: stage names and the agreement of a
// Monte Carlo batch with a stability check.
#include <saltus/sensitivity/analysis/reference_analysis.hpp>

namespace saltus {

const char* to_string(AnalysisStage stage) {
  switch (stage) {
    case AnalysisStage::Linearisation: return "linearisation";
    case AnalysisStage::JumpGains: return "jump gains";
    case AnalysisStage::TrackingDesign: return "tracking design";
    case AnalysisStage::StabilityCheck: return "stability check";
    case AnalysisStage::MonteCarlo: return "Monte Carlo";
  }
  return "?";
}

bool monte_carlo_agrees(StabilityVerdict verdict, const MonteCarloReport& batch, double predicted_rate,
                        bool compare_rate) {
  const bool verdict_ok = verdict == StabilityVerdict::Stable     ? batch.shrank == batch.kept_event_sequence
                          : verdict == StabilityVerdict::Unstable ? batch.grew > 0
                                                                  : true;
  const bool below_bound = !compare_rate || !(batch.observed_rate_max > predicted_rate + 1e-3);
  return batch.kept_event_sequence > 0 && verdict_ok && batch.max_log_discrepancy <= 0.05 && below_bound;
}

}  // namespace saltus
