// The trajectory's JSON read back (hybrid/vocabulary/trajectory_io.hpp): written complete
// (TrajectoryJsonOptions::complete), trajectory_from_json rebuilds it exactly: the same JSON when
// written again (every member is written), the dense output evaluating bit for bit as the original,
// every event's fields and transitions, the Zeno fields (non-finite ones among them) and
// completions; and a JSON it cannot rebuild from is refused by name.
#include "scenes/all_scenes.hpp"
#include "scenes/references.hpp"

#include <saltus/hybrid/vocabulary/trajectory_io.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <sstream>
#include <string>
#include <utility>

namespace saltus {
namespace {

bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

template <class V>
void expect_same_bits(const V& a, const V& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (Eigen::Index k = 0; k < a.size(); ++k) EXPECT_TRUE(same_bits(a[k], b[k])) << what << "[" << k << "]: " << a[k] << " vs " << b[k];
}

/// Writes `traj` complete, reads it back, and checks the copy against the original.
template <Scene S>
void expect_round_trip(const HybridTrajectory<S>& traj, const S& scene) {
  const TrajectoryJsonOptions complete{true};
  std::stringstream text;
  write_json(text, traj, scene, complete);
  const HybridTrajectory<S> back = read_json(text, scene);
  // Every member is written: the same JSON again, complete and summary alike.
  EXPECT_EQ(to_json(back, scene, complete).dump(), to_json(traj, scene, complete).dump());
  EXPECT_EQ(to_json(back, scene).dump(), to_json(traj, scene).dump());
  ASSERT_EQ(back.segment_count(), traj.segment_count());
  ASSERT_EQ(back.events.size(), traj.events.size());
  for (int i = 0; i < traj.segment_count(); ++i) {
    const Segment<S>&a = traj.segments[i], &b = back.segments[i];
    EXPECT_EQ(b.mode, a.mode) << "segment " << i;
    EXPECT_TRUE(same_bits(b.t_begin, a.t_begin) && same_bits(b.t_end, a.t_end)) << "segment " << i;
    ASSERT_EQ(b.x.size(), a.x.size()) << "segment " << i;
    for (std::size_t k = 0; k < a.x.size(); ++k) {
      const auto &p = a.x.pieces()[k], &q = b.x.pieces()[k];
      // The state there, bit for bit: at the step points and inside the step.
      for (double t : {p.t0, 0.5 * (p.t0 + p.t1), p.t1})
        expect_same_bits(back.state(i, t), traj.state(i, t), "segment " + std::to_string(i) + " at t = " + std::to_string(t));
      EXPECT_EQ(q.degree, p.degree);
    }
  }
  for (std::size_t e = 0; e < traj.events.size(); ++e) {
    const Event<S>&a = traj.events[e], &b = back.events[e];
    EXPECT_TRUE(same_bits(b.t, a.t)) << "event " << e;
    expect_same_bits(b.x_minus, a.x_minus, "x_minus of event " + std::to_string(e));
    expect_same_bits(b.x_plus, a.x_plus, "x_plus of event " + std::to_string(e));
    EXPECT_EQ(b.mode_before, a.mode_before);
    EXPECT_EQ(b.mode_after, a.mode_after);
    EXPECT_EQ(b.guards(), a.guards());
    EXPECT_EQ(b.impact(), a.impact());
    EXPECT_EQ(b.input_jump, a.input_jump);
    ASSERT_EQ(b.transitions.size(), a.transitions.size());
    for (std::size_t k = 0; k < a.transitions.size(); ++k) {
      EXPECT_EQ(b.transitions[k].impulse_mode, a.transitions[k].impulse_mode);
      EXPECT_EQ(b.transitions[k].zeno_completion, a.transitions[k].zeno_completion);
      EXPECT_EQ(b.transitions[k].impact_without_collision, a.transitions[k].impact_without_collision);
      for (int c = 0; c < S::nc; ++c) EXPECT_TRUE(same_bits(b.transitions[k].impulse[c].normal, a.transitions[k].impulse[c].normal));
    }
  }
  EXPECT_EQ(back.status, traj.status);
  EXPECT_TRUE(same_bits(back.zeno_time, traj.zeno_time) || (std::isnan(back.zeno_time) && std::isnan(traj.zeno_time)));
  for (auto [read, written] :
       {std::pair{back.zeno_time_uncertainty, traj.zeno_time_uncertainty},
        std::pair{back.zeno_time_extrapolation_uncertainty, traj.zeno_time_extrapolation_uncertainty},
        std::pair{back.zeno_time_integration_uncertainty, traj.zeno_time_integration_uncertainty}})
    EXPECT_TRUE(same_bits(read, written) || (std::isnan(read) && std::isnan(written)));
  ASSERT_EQ(back.zeno_completions.size(), traj.zeno_completions.size());
  for (std::size_t k = 0; k < traj.zeno_completions.size(); ++k) {
    EXPECT_EQ(back.zeno_completions[k].contacts, traj.zeno_completions[k].contacts);
    EXPECT_EQ(back.zeno_completions[k].event, traj.zeno_completions[k].event);
    EXPECT_TRUE(same_bits(back.zeno_completions[k].t, traj.zeno_completions[k].t));
  }
  expect_same_bits(back.final_state(), traj.final_state(), "final_state");
  EXPECT_EQ(back.input_breakpoints, traj.input_breakpoints);
  EXPECT_EQ(back.statistics.steps, traj.statistics.steps);
  EXPECT_FALSE(static_cast<bool>(back.input)) << "the input law is never written";
}

TEST(TrajectoryJson, PointMassWithFrictionRoundTrips) {
  auto ref = references::point_mass_with_friction();  // impact into slip, stick, slip, release
  expect_round_trip(ref.trajectory, ref.scene);
}

TEST(TrajectoryJson, PlankBoxAndHopperRoundTrip) {
  auto box = references::plank_box();
  expect_round_trip(box.trajectory, box.scene);
  auto hopper = references::hopper_push_off();  // a feedback law; stick, slip, release
  expect_round_trip(hopper.trajectory, hopper.scene);
}

// Four corners at once, sliding diagonally: the slip directions (dx, dy) of a spatial contact.
TEST(TrajectoryJson, SpatialBoxSlidingDiagonallyRoundTrips) {
  scenes::SpatialBox box;
  Vec<12> x0 = Vec<12>::Zero();
  x0[2] = 0.5 * box.parameters().size[2] + 0.1;
  x0[6] = 2.0;
  x0[7] = 1.0;
  Simulator<scenes::SpatialBox> sim(box, references::tight());
  const auto traj = sim.run(x0, 0.0, 1.0, zero_input<scenes::SpatialBox>());
  ASSERT_GE(traj.events.size(), 2u);
  ASSERT_EQ(traj.segments[1].mode[0].mode, ContactMode::Slip);
  EXPECT_NE(traj.segments[1].mode[0].slip_direction[1], 0.0);
  expect_round_trip(traj, box);
}

// The ball's accumulation, stopped (status zeno) and completed (a ZenoCompletion, its uncertainty),
// and a run without dense output (the segments rebuilt from the events' states).
TEST(TrajectoryJson, BouncingBallZenoCompletionAndNoDenseOutputRoundTrip) {
  scenes::BouncingBall ball;
  for (bool completion : {false, true}) {
    SimulationOptions o = references::tight();
    o.zeno_completion = completion;
    Simulator<scenes::BouncingBall> sim(ball, o);
    const auto traj = sim.run(Vec<2>(1.0, 0.0), 0.0, 5.0, zero_input<scenes::BouncingBall>());
    ASSERT_EQ(traj.status, completion ? SimulationStatus::Completed : SimulationStatus::Zeno);
    ASSERT_EQ(traj.zeno_completions.size(), completion ? 1u : 0u);
    expect_round_trip(traj, ball);
  }
  SimulationOptions o;
  o.record_dense_output = false;
  Simulator<scenes::BouncingBall> sim(ball, o);
  const auto sparse = sim.run(Vec<2>(1.0, 0.0), 0.0, 1.0, zero_input<scenes::BouncingBall>());
  expect_round_trip(sparse, ball);
  // A geometric Zeno estimate (infinite uncertainty) is written "inf" and read back as such.
  HybridTrajectory<scenes::BouncingBall> guess = sparse;
  guess.status = SimulationStatus::Zeno;
  guess.zeno_time = 1.25;
  guess.zeno_time_uncertainty = std::numeric_limits<double>::infinity();
  const nlohmann::ordered_json j = to_json(guess, ball, TrajectoryJsonOptions{true});
  EXPECT_EQ(j.at("zeno_time_uncertainty"), "inf");
  EXPECT_TRUE(to_json(guess, ball).at("zeno_time_uncertainty").is_null());  // the summary's null
  EXPECT_EQ(trajectory_from_json(nlohmann::json::parse(j.dump()), ball).zeno_time_uncertainty,
            std::numeric_limits<double>::infinity());
  // A JSON written before the uncertainty had its two parts reads them as NaN.
  nlohmann::json earlier = nlohmann::json::parse(j.dump());
  earlier.erase("zeno_time_extrapolation_uncertainty");
  earlier.erase("zeno_time_integration_uncertainty");
  const auto old = trajectory_from_json(earlier, ball);
  EXPECT_EQ(old.zeno_time_uncertainty, std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(old.zeno_time_extrapolation_uncertainty) && std::isnan(old.zeno_time_integration_uncertainty));
}

TEST(TrajectoryJson, RefusesWhatItCannotRebuild) {
  scenes::BouncingBall ball;
  Simulator<scenes::BouncingBall> sim(ball, SimulationOptions{});
  const auto traj = sim.run(Vec<2>(1.0, 0.0), 0.0, 1.0, zero_input<scenes::BouncingBall>());
  const auto expect_refused = [&](const nlohmann::json& j, const std::string& message) {
    try {
      (void)trajectory_from_json(j, ball);
      ADD_FAILURE() << "accepted, expected: " << message;
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  expect_refused(nlohmann::json::parse(to_json(traj, ball).dump()), "not written complete");
  const nlohmann::json good = nlohmann::json::parse(to_json(traj, ball, TrajectoryJsonOptions{true}).dump());
  auto j = good;
  j["segments"][0].erase("pieces");
  expect_refused(j, "segments[0] has no 'pieces'");
  j = good;
  j["events"][0]["x_plus"] = {0.0, 1.0, 2.0};
  expect_refused(j, "events[0].x_plus is not an array of 2 numbers");
  j = good;
  j["events"][0]["transitions"][0]["guards"][0]["kind"] = "bounce";
  expect_refused(j, "events[0].transitions[0].guards[0].kind 'bounce' is not a guard kind");
  j = good;
  j["events"][0]["transitions"][0]["guards"][0]["contact"] = 3;
  expect_refused(j, "guards[0].contact = 3 is not a contact index in [0, 1)");
  j = good;
  j["segments"][1]["contact_modes"][0]["mode"] = "closed";
  expect_refused(j, "segments[1].contact_modes[0].mode 'closed' is not open, stick or slip");
  j = good;
  j["segments"][0]["pieces"][0]["degree"] = 9;
  expect_refused(j, "segments[0].pieces[0].degree = 9 is outside [0, 5]");
  j = good;
  j["status"] = "done";
  expect_refused(j, "status 'done'");
  j = good;
  j["events"].push_back(j["events"][0]);
  j["events"].push_back(j["events"][0]);
  expect_refused(j, "events for");
  std::istringstream not_json("{\"status\": ");
  EXPECT_THROW((void)read_json(not_json, ball), InvalidArgument);
}

}  // namespace
}  // namespace saltus
