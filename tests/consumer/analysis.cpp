// A user's reference analysed through the installed headers: the user's scene (falling_mass.hpp)
// dropped from 2 m bounces once within 1 s; one call gives the jump gain of that impact, an LQR
// tracking design along the bounce, its stability check and 20 perturbed closed-loop runs. The
// program checks the verdict, the agreement with the runs and the JSON report's keys. Includes no
// definition of the machinery: it links falling_mass.cpp.
#include "falling_mass.hpp"

#include <saltus/hybrid/simulation/simulator.hpp>
#include <saltus/sensitivity/analysis/reference_analysis_io.hpp>

#include <cstdio>

int main() {
  const FallingMass scene;
  const saltus::SimulationOptions simulation;
  const auto reference =
      saltus::Simulator<FallingMass>(scene, simulation).run(saltus::Vec<2>(2.0, 0.0), 0.0, 1.0, saltus::zero_input<FallingMass>());

  saltus::ReferenceAnalysisOptions<FallingMass> options;
  options.design.name = "LQR, Q = I, R = 0.01";
  options.design.weights.R *= 0.01;
  options.monte_carlo.runs = 20;
  const auto analysis = saltus::analyse_reference(scene, reference, simulation, options);
  const nlohmann::ordered_json report = saltus::to_json(analysis);
  std::printf("%s\n", report.dump(2).c_str());

  int failures = 0;
  const auto expect = [&](bool ok, const char* what) {
    if (!ok) std::printf("analysis: %s does not hold\n", what);
    failures += ok ? 0 : 1;
  };
  expect(analysis.completed(), "every stage completed");
  expect(analysis.events.size() == 1 && !analysis.events[0].conewise, "one impact with a saltation matrix");
  expect(analysis.stability && analysis.stability->verdict == saltus::StabilityVerdict::Stable, "the verdict is stable");
  expect(analysis.agree, "the Monte Carlo runs agree with the verdict");
  for (const char* key : {"events", "design", "verdict", "upper_bound", "lower_bound", "predicted_rate", "monte_carlo",
                          "agree", "seconds"})
    expect(report.contains(key), key);
  return failures == 0 ? 0 : 1;
}

