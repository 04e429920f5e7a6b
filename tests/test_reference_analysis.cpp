// The analysis of a reference in one call (sensitivity/analysis/reference_analysis.hpp): on a cheap
// reference, so that it also runs under the sanitizers, the point mass of Example 3 (impact into a
// closed contact, slide, release; single-guard events) with an LQR design and a small batch; a
// failing stage reported by name, not thrown; the JSON writer's keys (reference_analysis_io.hpp);
// the norms of a conewise event's pieces (the plank-box's box landing flat); and the refusals of
// bad input. The conewise rows of the plank-box's optimal reference are checked in
// test_flagship_ocps.cpp.
#include "scenes/references.hpp"

#include <Eigen/Eigenvalues>  // operatorNorm
#include <Eigen/SVD>
#include <gtest/gtest.h>
#include <saltus/sensitivity/analysis/reference_analysis.hpp>
#include <saltus/sensitivity/analysis/reference_analysis_io.hpp>

#include <cmath>
#include <string>
#include <vector>

using namespace saltus;
using scenes::PointMass;

namespace {

/// The keys of a JSON object, in order.
std::vector<std::string> keys(const nlohmann::ordered_json& j) {
  std::vector<std::string> k;
  for (const auto& item : j.items()) k.push_back(item.key());
  return k;
}

/// Q = I, R = 0.1 I along Example 3 (the README's tracking row), `runs` closed-loop runs.
ReferenceAnalysisOptions<PointMass> example3_lqr(int runs) {
  ReferenceAnalysisOptions<PointMass> options;
  options.design.name = "LQR, Q = I, R = 0.1 I";
  options.design.weights.R *= 0.1;
  options.monte_carlo.runs = runs;
  options.spreading = 0.1;
  return options;
}

/// analyse_reference refuses (InvalidArgument) with a message that contains `names`.
void expect_refused(const references::Reference<PointMass>& ref, const ReferenceAnalysisOptions<PointMass>& options,
                    const std::string& names) {
  try {
    analyse_reference(ref.scene, ref.trajectory, ref.options, options);
    ADD_FAILURE() << "accepted; expected InvalidArgument naming " << names;
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(OcpAnalysis, PointMassExample3IsStableAndAgreesWithMonteCarlo) {
  const auto ref = references::example3();
  const ReferenceAnalysis<PointMass> a = analyse_reference(ref.scene, ref.trajectory, ref.options, example3_lqr(20));
  const std::string dump = to_json(a).dump(2);
  ASSERT_TRUE(a.completed()) << dump;
  ASSERT_EQ(a.events.size(), ref.trajectory.events.size());
  for (const EventGainSummary& e : a.events) {
    EXPECT_FALSE(e.conewise) << dump;
    EXPECT_TRUE(std::isfinite(e.saltation_norm)) << dump;
  }
  EXPECT_EQ(a.stability->verdict, StabilityVerdict::Stable) << dump;
  EXPECT_EQ(a.stability->lower_bound, a.stability->upper_bound);  // no simultaneous event
  EXPECT_EQ(a.monte_carlo->kept_event_sequence, 20) << dump;
  EXPECT_EQ(a.monte_carlo->shrank, 20) << dump;
  EXPECT_TRUE(a.agree) << dump;
}

TEST(OcpAnalysis, AFailingStageIsReportedWithItsName) {
  const auto ref = references::example3();
  ReferenceAnalysisOptions<PointMass> options;
  options.design.name = "LQR with R not positive definite";
  options.design.weights.R = -options.design.weights.R;
  const ReferenceAnalysis<PointMass> a = analyse_reference(ref.scene, ref.trajectory, ref.options, options);
  ASSERT_FALSE(a.completed()) << to_json(a).dump(2);
  ASSERT_TRUE(a.failed_at.has_value());
  EXPECT_STREQ(to_string(*a.failed_at), "tracking design");
  EXPECT_NE(a.failure.find("R"), std::string::npos) << a.failure;
  EXPECT_EQ(a.events.size(), ref.trajectory.events.size());  // what came before the failure is kept
  EXPECT_FALSE(a.stability.has_value());
}

// The keys of today's `plank_box --json` "analysis" object, in its order, for a completed analysis
// and for one that failed at the tracking design.
TEST(ReferenceAnalysis, JsonKeepsTheKeysOfEachCompletedStage) {
  const auto ref = references::example3();
  const ReferenceAnalysis<PointMass> analysis = analyse_reference(ref.scene, ref.trajectory, ref.options, example3_lqr(4));
  const nlohmann::ordered_json j = to_json(analysis);
  EXPECT_EQ(keys(j), (std::vector<std::string>{"linearisation_seconds", "events", "jump_gain_seconds", "design",
                                               "lqr_seconds", "verdict", "upper_bound", "lower_bound", "predicted_rate",
                                               "peak_amplification", "check_seconds", "monte_carlo", "agree", "seconds"}))
      << j.dump(2);
  ASSERT_EQ(j["events"].size(), ref.trajectory.events.size());
  EXPECT_EQ(keys(j["events"][0]), (std::vector<std::string>{"t", "guards", "conewise", "saltation_norm"}));
  EXPECT_EQ(j["events"][0]["t"].get<double>(), ref.trajectory.events[0].t);
  EXPECT_EQ(j["events"][0]["guards"].get<int>(), 1);
  EXPECT_EQ(keys(j["monte_carlo"]),
            (std::vector<std::string>{"runs", "kept_event_sequence", "failed", "failure_reasons", "departures", "grew", "shrank",
                                      "observed_rate_max", "predicted_rate_max", "max_log_discrepancy",
                                      "relative_to_nominal_run", "nominal_run_deviation", "nominal_run_max_deviation",
                                      "nominal_run_departure", "perturbation_size", "simulation_seconds", "seconds", "threads",
                                      "amplifications"}));
  EXPECT_EQ(j["monte_carlo"]["runs"].get<int>(), 4);
  // One entry per run that did not fail, the run's own numbers in the run's order.
  const auto& amplifications = j["monte_carlo"]["amplifications"];
  EXPECT_EQ(keys(amplifications), (std::vector<std::string>{"predicted", "observed", "kept_event_sequence"}));
  ASSERT_TRUE(analysis.monte_carlo.has_value());
  std::size_t k = 0;
  for (const MonteCarloRun& run : analysis.monte_carlo->run) {
    if (run.failed) continue;
    ASSERT_LT(k, amplifications["predicted"].size());
    EXPECT_EQ(amplifications["predicted"][k].get<double>(), run.predicted);
    EXPECT_EQ(amplifications["observed"][k].get<double>(), run.observed);
    EXPECT_EQ(amplifications["kept_event_sequence"][k].get<bool>(), run.kept_event_sequence);
    ++k;
  }
  EXPECT_EQ(k, amplifications["observed"].size());
  EXPECT_EQ(k, 4u - static_cast<std::size_t>(j["monte_carlo"]["failed"].get<int>()));
  EXPECT_EQ(j["monte_carlo"]["perturbation_size"].get<double>(), 1e-4);
  EXPECT_EQ(j["design"].get<std::string>(), "LQR, Q = I, R = 0.1 I");
  EXPECT_EQ(j["verdict"].get<std::string>(), "stable");

  ReferenceAnalysisOptions<PointMass> refused = example3_lqr(4);
  refused.design.weights.R = -refused.design.weights.R;
  const nlohmann::ordered_json f = to_json(analyse_reference(ref.scene, ref.trajectory, ref.options, refused));
  EXPECT_EQ(keys(f), (std::vector<std::string>{"linearisation_seconds", "events", "jump_gain_seconds", "failure",
                                               "failed_at", "seconds"}))
      << f.dump(2);
  EXPECT_EQ(f["failed_at"].get<std::string>(), "tracking design");
}

// The plank-box's box lowered flat onto the plank: both corners land at once, a conewise event of
// two pieces (one per corner landing first). Its row carries the spectral norm of each piece's G_z,
// in the order of the conewise gain's pieces(): checked against the pieces of the same linearisation
// built here (and each norm against the largest singular value), in the report and in its JSON.
// The design is refused (R negative), so the analysis stops after the jump gains.
TEST(ReferenceAnalysis, ConewiseRowHasTheNormOfEachPiece) {
  using scenes::PlankBox;
  const PlankBox plank_box;
  const SimulationOptions simulation = references::tight();
  Simulator<PlankBox> simulator(plank_box, simulation);
  const auto traj = simulator.run(plank_box.flat_state(), 0.0, 0.3,
                                  open_loop<PlankBox>([&](double) { return plank_box.lowering_input(); }));
  ASSERT_EQ(traj.events.size(), 1u) << "one event: the flat landing";
  ReferenceAnalysisOptions<PlankBox> options;
  options.design.name = "refused: R negative";
  options.design.weights.R = -options.design.weights.R;
  const ReferenceAnalysis<PlankBox> a = analyse_reference(plank_box, traj, simulation, options);
  const nlohmann::ordered_json j = to_json(a);
  ASSERT_EQ(a.failed_at, AnalysisStage::TrackingDesign) << j.dump(2);
  ASSERT_EQ(a.events.size(), 1u);
  const EventGainSummary& row = a.events[0];
  ASSERT_TRUE(row.conewise) << j.dump(2);

  LinearisationOptions lo;  // analyse_reference's linearisation
  lo.gains.feedback = FeedbackTreatment::Signal;
  lo.simulation = simulation;
  lo.spreading.before = lo.spreading.after = options.spreading;
  const LinearisedSystem<PlankBox> lin(plank_box, traj, lo);
  ASSERT_TRUE(lin.conewise(0));
  ConewiseJumpGain<PlankBox>& gain = lin.conewise_gain(0);
  ASSERT_EQ(gain.build_all(), 2);
  ASSERT_EQ(row.pieces, 2);
  ASSERT_EQ(row.piece_norms.size(), gain.pieces().size());
  ASSERT_EQ(j["events"][0]["piece_norms"].size(), gain.pieces().size());
  for (std::size_t k = 0; k < gain.pieces().size(); ++k) {
    const Mat<8, 8>& G_z = gain.pieces()[k]->G_z;
    const double largest_singular_value = Eigen::JacobiSVD<Mat<8, 8>>(G_z).singularValues()[0];
    EXPECT_EQ(row.piece_norms[k], G_z.operatorNorm()) << "piece " << k << "\nG_z =\n" << G_z;
    EXPECT_NEAR(row.piece_norms[k], largest_singular_value, 1e-12 * largest_singular_value) << "piece " << k;
    EXPECT_EQ(j["events"][0]["piece_norms"][k].get<double>(), row.piece_norms[k]);
  }
  EXPECT_NE(row.piece_norms[0], row.piece_norms[1]) << "the two landing orders have different gains";
}

// A conewise row (written by hand: the writer's own contract) has its pieces, their norms, unrealisable orders
// and face discontinuity, null when no face was compared; a failure in the first stage leaves only
// the failure and the time.
TEST(ReferenceAnalysis, JsonOfConewiseRowsAndOfAFailedLinearisation) {
  ReferenceAnalysis<PointMass> a;
  EventGainSummary compared, uncompared;
  compared.t = 0.25;
  compared.guards = 2;
  compared.conewise = true;
  compared.pieces = 2;
  compared.piece_norms = {1.5, 3.25};
  compared.unrealisable_orders = 1;
  compared.face_discontinuity = 2.5e-15;
  uncompared = compared;
  uncompared.face_discontinuity.reset();
  a.events = {compared, uncompared};
  a.failed_at = AnalysisStage::TrackingDesign;
  a.failure = "stopped here";
  const nlohmann::ordered_json j = to_json(a);
  ASSERT_EQ(j["events"].size(), 2u);
  EXPECT_EQ(keys(j["events"][0]), (std::vector<std::string>{"t", "guards", "conewise", "pieces", "piece_norms",
                                                            "unrealisable_orders", "face_discontinuity"}));
  EXPECT_EQ(j["events"][0]["piece_norms"].get<std::vector<double>>(), (std::vector<double>{1.5, 3.25}));
  EXPECT_EQ(j["events"][0]["face_discontinuity"].get<double>(), 2.5e-15);
  EXPECT_TRUE(j["events"][1]["face_discontinuity"].is_null());
  EXPECT_EQ(j["events"][0]["pieces"].get<int>(), 2);

  a.failed_at = AnalysisStage::Linearisation;
  EXPECT_EQ(keys(to_json(a)), (std::vector<std::string>{"failure", "failed_at", "seconds"}));
  EXPECT_EQ(to_json(a)["failed_at"].get<std::string>(), "linearisation");
}

TEST(ReferenceAnalysis, RefusesAnEmptyOrInconsistentTrajectory) {
  auto ref = references::example3();
  const ReferenceAnalysisOptions<PointMass> options = example3_lqr(4);
  auto empty = ref;
  empty.trajectory = HybridTrajectory<PointMass>{};
  expect_refused(empty, options, "empty trajectory");
  auto no_input = ref;
  no_input.trajectory.input = nullptr;
  expect_refused(no_input, options, "no input law");
  auto lost_event = ref;
  lost_event.trajectory.events.pop_back();
  expect_refused(lost_event, options, "one event fewer than segments");
}

TEST(ReferenceAnalysis, RefusesMismatchedOptions) {
  const auto ref = references::example3();
  using Subspace = Eigen::Matrix<double, 4, Eigen::Dynamic, 0, 4, 4>;
  {
    auto o = example3_lqr(4);
    o.stability.initial_subspace = Subspace(4, 0);
    expect_refused(ref, o, "initial_subspace has 0 columns");
  }
  {
    auto o = example3_lqr(4);  // the batch perturbs x, the check only the velocities
    Subspace E = Subspace::Zero(4, 2);
    E(2, 0) = E(3, 1) = 1.0;
    o.stability.initial_subspace = E;
    expect_refused(ref, o, "scale perturbs coordinate 0");
  }
  {
    auto o = example3_lqr(4);
    o.monte_carlo.weight *= 2.0;
    expect_refused(ref, o, "monte_carlo.weight differs from options.stability.weight");
  }
  {
    auto o = example3_lqr(4);
    o.stability.output_weight = Mat<4, 4>(Vec<4>(1, 1, 0, 0).asDiagonal());
    expect_refused(ref, o, "output weights W_out");
  }
  {
    auto o = example3_lqr(0);
    expect_refused(ref, o, "monte_carlo.runs must be >= 1, got 0");
  }
  {
    auto o = example3_lqr(4);
    o.monte_carlo.size = 0.0;
    expect_refused(ref, o, "monte_carlo.size must be > 0");
  }
  {
    auto o = example3_lqr(4);
    o.monte_carlo.t_final = ref.trajectory.t_end() + 1.0;
    expect_refused(ref, o, "is outside the reference");
  }
  {
    auto o = example3_lqr(4);
    o.spreading = -0.1;
    expect_refused(ref, o, "spreading must be finite and >= 0");
  }
}
