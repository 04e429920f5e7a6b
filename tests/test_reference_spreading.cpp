// Reference spreading (each segment extended by its own mode's flow) against closed forms, the
// import of a reference from CSV with its polishing by re-simulation, and a trajectory's JSON.
#include "support.hpp"

#include "scenes/all_scenes.hpp"

#include <saltus/hybrid/dynamics/contact_forces_csv.hpp>
#include <saltus/hybrid/vocabulary/trajectory_io.hpp>

#include <nlohmann/json.hpp>

#include <sstream>

namespace saltus::testing {
namespace {

constexpr double g = 9.81;

SimulationOptions tight(IntegratorKind kind = IntegratorKind::DormandPrince) {
  SimulationOptions o;
  o.integrator.kind = kind;
  o.integrator.relative_tolerance = 1e-12;
  o.integrator.absolute_tolerance = 1e-13;
  return o;
}

// The ball's pre-impact segment, extended past the impact, keeps falling below the ground on the
// free-fall parabola; extended before t = 0 it is the same parabola run backwards. The bounce's
// segment extended before the impact is the post-impact parabola, also below the ground.
TEST(ReferenceSpreading, ExtendsTheBouncingBallsSegmentsOnTheirParabolas) {
  scenes::BouncingBall ball;  // e_n = 0.5
  const double e = ball.parameters().restitution;
  SimulationOptions o = tight();
  o.max_events = 2;
  Simulator<scenes::BouncingBall> sim(ball, o);
  const auto traj = sim.run(Vec<2>(1.0, 0.0), 0.0, 1.5, zero_input<scenes::BouncingBall>());
  ASSERT_GE(traj.events.size(), 2u);
  ExtensionOptions eo;
  eo.before = 0.1;
  eo.after = 0.2;
  const ExtendedReference<scenes::BouncingBall> ext(ball, traj, eo);
  const double t1 = std::sqrt(2.0 / g), v_plus = e * std::sqrt(2 * g);
  EXPECT_NEAR(ext.t_end(0), t1 + 0.2, 1e-12);
  EXPECT_NEAR(ext.t_begin(0), -0.1, 1e-12);
  for (double t : {-0.1, -0.03, 0.2, t1 + 0.01, t1 + 0.1, t1 + 0.2}) {
    const Vec<2> free_fall(1 - 0.5 * g * t * t, -g * t);
    EXPECT_TRUE(matrices_near(ext.state(0, t), free_fall, 0.0, 1e-10)) << "t = " << t;
  }
  EXPECT_LT(ext.state(0, t1 + 0.1)[0], -0.4) << "below the ground";
  for (double t : {t1 - 0.1, t1 - 0.01, t1 + 0.1}) {
    const double s = t - t1;
    EXPECT_TRUE(matrices_near(ext.state(1, t), Vec<2>(v_plus * s - 0.5 * g * s * s, v_plus - g * s), 0.0, 1e-10))
        << "t = " << t;
  }
  EXPECT_THROW(ext.state(0, t1 + 0.3), InvalidArgument);
  EXPECT_THROW(ext.state(0, -0.2), InvalidArgument);
  EXPECT_THROW(ext.state(5, 0.1), InvalidArgument);
}

// The inelastic ball's resting segment extended before the impact rests on the ground (the
// closed mode's flow keeps it there).
TEST(ReferenceSpreading, ExtendsARestingSegmentBackwardsAtRest) {
  scenes::BouncingBallParameters p;
  p.restitution = 0.0;
  scenes::BouncingBall ball(p);
  Simulator<scenes::BouncingBall> sim(ball, tight());
  const auto traj = sim.run(Vec<2>(1.0, 0.0), 0.0, 1.0, zero_input<scenes::BouncingBall>());
  ASSERT_EQ(traj.segment_count(), 2);
  const ExtendedReference<scenes::BouncingBall> ext(ball, traj);
  const double t1 = std::sqrt(2.0 / g);
  EXPECT_TRUE(matrices_near(ext.state(1, t1 - 0.04), Vec<2>(0.0, 0.0), 0.0, 1e-12));
}

// Example 3: the free-flight segment after lift-off (t = 1.5) extended backwards. Under
// Evaluate, u2 = 2 g (t - 1) keeps ramping and the height follows g (t - 1.5)^3 / 3 below the
// table; under Hold, u2 = u2(1.5) = m g cancels gravity and the mass stays at height 0.
TEST(ReferenceSpreading, HoldAndEvaluateExtendTheInputAsDocumented) {
  scenes::PointMass mass;
  auto input = open_loop<scenes::PointMass>([](double t) { return Vec<2>(7.0, t < 1.0 ? 0.0 : 2 * g * (t - 1.0)); });
  SimulationOptions o = tight();
  o.breakpoints = {1.0};
  Simulator<scenes::PointMass> sim(mass, o);
  const auto traj = sim.run(Vec<4>(0.0, 1.0, 0.0, 0.0), 0.0, 2.0, input);
  ASSERT_EQ(traj.segment_count(), 3);
  ExtensionOptions eo;
  eo.before = 0.05;
  eo.after = 0.05;
  eo.input = InputExtension::Evaluate;
  const ExtendedReference<scenes::PointMass> evaluate(mass, traj, eo);
  eo.input = InputExtension::Hold;
  const ExtendedReference<scenes::PointMass> hold(mass, traj, eo);
  for (double t : {1.46, 1.48, 1.499}) {
    const double s = t - 1.5;
    EXPECT_TRUE(matrices_near(evaluate.state(2, t), Vec<4>(3.5 * t * t, g * s * s * s / 3, 7 * t, g * s * s), 0.0, 1e-10))
        << "t = " << t;
    EXPECT_TRUE(matrices_near(hold.state(2, t), Vec<4>(3.5 * t * t, 0.0, 7 * t, 0.0), 0.0, 1e-10)) << "t = " << t;
    EXPECT_TRUE(matrices_near(evaluate.input(2, t), Vec<2>(7.0, 2 * g * (t - 1)), 0.0, 1e-12));
    EXPECT_TRUE(matrices_near(hold.input(2, t), Vec<2>(7.0, g), 0.0, 1e-12));
  }
  // The sliding segment extended past lift-off stays on the table (its closed mode's flow).
  EXPECT_TRUE(matrices_near(evaluate.state(1, 1.54), Vec<4>(3.5 * 1.54 * 1.54, 0.0, 7 * 1.54, 0.0), 0.0, 1e-10));
  // Inside a segment the extension is the reference itself.
  EXPECT_TRUE(matrices_near(evaluate.state(1, 1.2), traj.state(1, 1.2), 0.0, 0.0));
}

TEST(ReferenceSpreading, BadOptionsAreRejected) {
  scenes::BouncingBall ball;
  Simulator<scenes::BouncingBall> sim(ball, tight());
  const auto traj = sim.run(Vec<2>(1.0, 0.0), 0.0, 0.3, zero_input<scenes::BouncingBall>());
  ExtensionOptions eo;
  eo.before = -0.1;
  EXPECT_THROW((ExtendedReference<scenes::BouncingBall>(ball, traj, eo)), InvalidArgument);
  eo.before = 0.1;
  eo.after = std::nan("");
  EXPECT_THROW((ExtendedReference<scenes::BouncingBall>(ball, traj, eo)), InvalidArgument);
  HybridTrajectory<scenes::BouncingBall> empty;
  EXPECT_THROW((ExtendedReference<scenes::BouncingBall>(ball, empty)), InvalidArgument);
}

// ---- import and polish ---------------------------------------------------------------------

HybridTrajectory<scenes::PointMass> example3(const SimulationOptions& base = tight()) {
  scenes::PointMass mass;
  auto input = open_loop<scenes::PointMass>([](double t) { return Vec<2>(7.0, t < 1.0 ? 0.0 : 2 * g * (t - 1.0)); });
  SimulationOptions o = base;
  o.breakpoints = {1.0};
  Simulator<scenes::PointMass> sim(mass, o);
  return sim.run(Vec<4>(0.0, 1.0, 0.0, 0.0), 0.0, 2.0, input);
}

TEST(ReferenceImport, CsvRoundTripIsExact) {
  scenes::PointMass mass;
  const auto traj = example3();
  std::stringstream csv;
  write_csv(csv, traj, 0.01, mass);
  const auto ref = read_reference_csv<scenes::PointMass>(csv);
  ASSERT_EQ(ref.event_times.size(), traj.events.size());
  for (std::size_t e = 0; e < traj.events.size(); ++e) EXPECT_EQ(ref.event_times[e], traj.events[e].t);
  ASSERT_GT(ref.size(), 150u);
  for (std::size_t k = 0; k < ref.size(); ++k) {
    const int s = ref.segment_of(k);
    ASSERT_LT(s, traj.segment_count());
    EXPECT_TRUE(matrices_near(ref.x[k], traj.state(s, ref.t[k]), 0.0, 0.0)) << "sample " << k;
    EXPECT_TRUE(matrices_near(ref.u[k], traj.input_at(s, ref.t[k]), 0.0, 0.0)) << "sample " << k;
  }
}

// write_json's output parses back to the trajectory: its events, their times to the last bit and
// the guards by contact name.
TEST(TrajectoryJson, ParsesBackToTheTrajectory) {
  scenes::PointMass mass;
  const auto traj = example3();
  ASSERT_EQ(traj.events.size(), 2u);
  std::stringstream out;
  write_json(out, traj, mass);
  const std::string text = out.str();
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.find('\n'), text.size() - 1) << "one line, then a newline";
  const nlohmann::json j = nlohmann::json::parse(text);
  EXPECT_EQ(j.at("status"), "completed");
  ASSERT_EQ(j.at("events").size(), traj.events.size());
  for (std::size_t e = 0; e < traj.events.size(); ++e) {
    const auto& ev = j.at("events").at(e);
    EXPECT_EQ(ev.at("t").get<double>(), traj.events[e].t) << "event " << e;
    const auto guards = traj.events[e].guards();
    ASSERT_EQ(ev.at("guards").size(), guards.size()) << "event " << e;
    ASSERT_FALSE(guards.empty());
    EXPECT_EQ(ev.at("guards").at(0).at("contact"), mass.contact(guards[0].contact).name) << "event " << e;
    EXPECT_EQ(ev.at("guards").at(0).at("kind"), to_string(guards[0].kind)) << "event " << e;
    EXPECT_EQ(ev.at("x_plus").at(1).get<double>(), traj.events[e].x_plus[1]) << "event " << e;
  }
  EXPECT_TRUE(j.at("events").at(0).at("impact").get<bool>());
  EXPECT_TRUE(j.at("zeno_time").is_null());
}

// The point mass of example3 falls from 1 m (thrust 7 N sideways), lands at t = sqrt(2 / g) with the
// impulse m sqrt(2 g) (e = 0), slides on the frictionless table with the normal force
// m g - u_z = g (1 - 2 (t - 1)_+) and leaves it at t = 1.5: the forces CSV and the impulse in the
// JSON events against these closed forms.
TEST(TrajectoryReport, ContactForcesAndImpulsesAgainstClosedForms) {
  scenes::PointMass mass;
  const auto traj = example3();
  ASSERT_EQ(traj.events.size(), 2u);
  std::stringstream csv;
  write_contact_forces_csv(csv, traj, 0.01, mass);
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "t,segment,table_n");
  int rows = 0, inside_slide = 0;
  while (std::getline(csv, line)) {
    double t = 0.0, force = 0.0;
    int segment = -1;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%d,%lf", &t, &segment, &force), 3) << line;
    const double expected = segment == 1 ? g * (1.0 - 2.0 * std::max(0.0, t - 1.0)) : 0.0;
    EXPECT_NEAR(force, expected, 1e-9) << "t = " << t << ", segment " << segment;
    inside_slide += segment == 1;
    ++rows;
  }
  EXPECT_GT(rows, 200);
  EXPECT_GT(inside_slide, 100);
  const nlohmann::json j = to_json(traj, mass);
  const auto& landing = j.at("events").at(0).at("impulses");
  ASSERT_EQ(landing.size(), 1u);
  EXPECT_EQ(landing.at(0).at("contact"), "table");
  EXPECT_NEAR(landing.at(0).at("normal").get<double>(), std::sqrt(2.0 * g), 1e-9);
  EXPECT_TRUE(landing.at(0).at("tangent").empty());
  EXPECT_TRUE(j.at("events").at(1).at("impulses").empty()) << "the lift-off takes no impulse";
  EXPECT_THROW(write_contact_forces_csv(csv, traj, 0.0, mass), InvalidArgument);
}

// The spatial box's slip modes are written with their direction "(dx,dy)": quoted, so the CSV
// still parses.
TEST(ReferenceImport, ReadsModesWithCommas) {
  scenes::SpatialBox box;
  Vec<12> x0 = Vec<12>::Zero();
  x0[2] = 0.5 * box.parameters().size[2];
  x0[6] = 1.2;
  Simulator<scenes::SpatialBox> sim(box, tight());
  const auto traj = sim.run(x0, 0.0, 0.4, zero_input<scenes::SpatialBox>());
  std::stringstream csv;
  write_csv(csv, traj, 0.02, box);
  EXPECT_NE(csv.str().find("(1,0)"), std::string::npos) << csv.str().substr(0, 400);
  const auto ref = read_reference_csv<scenes::SpatialBox>(csv);
  ASSERT_EQ(ref.event_times.size(), traj.events.size());
  EXPECT_TRUE(matrices_near(ref.x.back(), traj.final_state(), 0.0, 1e-14));
}

TEST(ReferenceImport, MalformedCsvIsRejected) {
  auto read = [](const std::string& text) {
    std::istringstream in(text);
    return read_reference_csv<scenes::BouncingBall>(in);
  };
  EXPECT_NO_THROW(read("t,q0,v0\n0,1,0\n0.1,0.95,-0.98\n"));
  EXPECT_THROW(read(""), InvalidArgument);
  EXPECT_THROW(read("t,q0\n0,1\n0.1,0.9\n"), InvalidArgument);                 // no v0
  EXPECT_THROW(read("t,q0,v0\n0,1,0\n0.1,zero,-0.98\n"), InvalidArgument);     // not a number
  EXPECT_THROW(read("t,q0,v0\n0,1,0\n-0.1,0.95,-0.98\n"), InvalidArgument);    // time decreases
  EXPECT_THROW(read("t,q0,v0\n0,1,0\n0.1,0.95\n"), InvalidArgument);           // missing field
  EXPECT_THROW(read("t,q0,v0\n0,1,0\n"), InvalidArgument);                     // one sample
}

// A reference written at 0.01 s and polished: its input is piecewise linear in t except at the
// kink t = 1, which the samples bracket; re-simulated under the interpolated input it comes back
// to the written states and event times.
TEST(ReferenceImport, PolishReproducesAnImportedReference) {
  scenes::PointMass mass;
  const auto traj = example3();
  std::stringstream csv;
  write_csv(csv, traj, 0.01, mass);
  const auto ref = read_reference_csv<scenes::PointMass>(csv);
  for (IntegratorKind kind : {IntegratorKind::DormandPrince, IntegratorKind::CvodeBdf}) {
    const auto polished = polish(mass, ref, tight(kind));
    EXPECT_EQ(polished.simulated_events, 2u) << to_string(kind);
    EXPECT_LT(polished.event_time_distance, 1e-9) << to_string(kind);
    EXPECT_LT(polished.state_distance, 1e-6) << to_string(kind);
    EXPECT_TRUE(matrices_near(polished.trajectory.final_state(), traj.final_state(), 0.0, 1e-6)) << to_string(kind);
  }
  // A perturbed sample, and a reference missing an event, are reported as such.
  auto perturbed = ref;
  perturbed.x[40][0] += 1e-3;
  EXPECT_GE(polish(mass, perturbed, tight()).state_distance, 1e-3 * 0.999);
  auto missing = ref;
  missing.event_times.pop_back();
  missing.segment.clear();
  EXPECT_TRUE(std::isinf(polish(mass, missing, tight()).event_time_distance));
  // With an event missing, the remaining one still pairs with the first simulated event: the
  // impact's samples, stamped 1e-9 s after the simulated impact, are compared with the segments
  // spread over that difference, not with the post-impact state (a 4.4 m/s "distance").
  const double t_impact = missing.event_times.front();
  for (std::size_t k = 0; k < missing.size(); ++k)
    if (missing.t[k] == t_impact) missing.t[k] += 1e-9;
  missing.event_times.front() += 1e-9;
  const auto late = polish(mass, missing, tight());
  EXPECT_TRUE(std::isinf(late.event_time_distance));
  EXPECT_LT(late.state_distance, 1e-6);
}

}  // namespace
}  // namespace saltus::testing
