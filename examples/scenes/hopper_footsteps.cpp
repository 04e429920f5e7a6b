// The hopper's footstep guess (declared in hopper_footsteps.hpp).
#include "scenes/hopper_footsteps.hpp"

#include <saltus/timefreezing/refinement/mode_schedule.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace saltus::scenes {

namespace {

/// One phase of the guessed gait: a stance on footholds[index] or the flight after it.
struct GaitPhase {
  double begin = 0.0, end = 0.0;
  bool stance = true;
  int index = 0;
};

/// The hopper's leg geometry and the gait's poses (file comment of hopper_footsteps.hpp).
class FootstepGait {
 public:
  FootstepGait(const Hopper& hopper, const HopperFootsteps& steps, const Vec<4>& q_start, const Vec<4>& q_end,
               const HopperGaitShape& shape)
      : thigh_(hopper.parameters().thigh_length), shank_(hopper.parameters().shank_length), steps_(steps),
        shape_(shape), start_(q_start), end_(q_end) {}

  /// (x, z, phi_hip, phi_knee) of phase p at time t.
  Vec<4> pose(const GaitPhase& p, double t) const { return p.stance ? stance_pose(p, t) : flight_pose(p, t); }

 private:
  /// (phi_hip, phi_knee) that put the foot at (fx, 0) below a hip at (hx, hz), the knee bent forward.
  Vec<2> leg_angles_reaching(double hx, double hz, double fx) const {
    const double rx = fx - hx, rz = -hz, reach = std::min(std::hypot(rx, rz), thigh_ + shank_);
    const double cos_knee = (reach * reach - thigh_ * thigh_ - shank_ * shank_) / (2 * thigh_ * shank_);
    const double knee = -std::acos(std::clamp(cos_knee, -1.0, 1.0));
    const double inner = std::atan2(shank_ * std::sin(-knee), thigh_ + shank_ * std::cos(knee));
    return Vec<2>(std::atan2(rx, -rz) + inner, knee);
  }
  double foothold(int i) const { return steps_.footholds[static_cast<std::size_t>(i)]; }
  int last() const { return static_cast<int>(steps_.footholds.size()) - 1; }

  Vec<4> stance_pose(const GaitPhase& p, double t) const {
    const double s = (t - p.begin) / (p.end - p.begin), x = foothold(p.index);
    const double from = p.index == 0 ? start_[0] : x - shape_.hip_offset;
    const double to = p.index == last() ? end_[0] : x + shape_.hip_offset;
    const double leg_from = p.index == 0 ? std::hypot(start_[0] - x, start_[1]) : shape_.stance_leg;
    const double leg_to = p.index == last() ? std::hypot(end_[0] - x, end_[1]) : shape_.stance_leg;
    const double leg = leg_from + (leg_to - leg_from) * s, hx = from + (to - from) * s;
    const double hz = std::sqrt(std::max(0.04, leg * leg - (hx - x) * (hx - x)));
    const Vec<2> a = leg_angles_reaching(hx, hz, x);
    return Vec<4>(hx, hz, a[0], a[1]);
  }

  Vec<4> flight_pose(const GaitPhase& p, double t) const {
    const double s = (t - p.begin) / (p.end - p.begin);
    const double z0 = std::sqrt(shape_.stance_leg * shape_.stance_leg - shape_.hip_offset * shape_.hip_offset);
    const double x0 = foothold(p.index) + shape_.hip_offset, x1 = foothold(p.index + 1) - shape_.hip_offset;
    const Vec<2> a0 = leg_angles_reaching(x0, z0, foothold(p.index));
    const Vec<2> a1 = leg_angles_reaching(x1, z0, foothold(p.index + 1));
    const double hz = std::min(0.54, z0 + 0.5 * 9.81 * (t - p.begin) * (p.end - t));
    const Vec<2> a = a0 + (a1 - a0) * s;
    return Vec<4>(x0 + (x1 - x0) * s, hz, a[0], a[1]);
  }

  double thigh_, shank_;
  HopperFootsteps steps_;
  HopperGaitShape shape_;
  Vec<4> start_, end_;
};

void validate(const Hopper& hopper, const HopperFootsteps& steps, double T, const HopperGaitShape& shape) {
  SALTUS_REQUIRE(!steps.footholds.empty(), "footstep_guess: no foothold");
  SALTUS_REQUIRE(steps.event_times.size() == 2 * (steps.footholds.size() - 1), "footstep_guess: ",
                 steps.footholds.size(), " footholds need ", 2 * (steps.footholds.size() - 1), " event times, got ",
                 steps.event_times.size());
  SALTUS_REQUIRE(std::isfinite(T) && T > 0.0, "footstep_guess: the horizon must be finite and > 0, got ", T);
  for (double x : steps.footholds) SALTUS_REQUIRE(std::isfinite(x), "footstep_guess: a foothold is not finite");
  double previous = 0.0;
  for (double t : steps.event_times) {
    SALTUS_REQUIRE(std::isfinite(t) && t > previous && t < T, "footstep_guess: event times must increase strictly inside (0, ",
                   T, "), got ", t, " after ", previous);
    previous = t;
  }
  const double leg = hopper.parameters().thigh_length + hopper.parameters().shank_length;
  SALTUS_REQUIRE(shape.stance_leg > 0.0 && shape.stance_leg < leg, "footstep_guess: stance_leg must be in (0, ", leg,
                 "), got ", shape.stance_leg);
  SALTUS_REQUIRE(shape.hip_offset >= 0.0 && shape.hip_offset < shape.stance_leg,
                 "footstep_guess: hip_offset must be in [0, stance_leg), got ", shape.hip_offset);
}

}  // namespace

timefreezing::ScheduleGuess<Hopper> footstep_guess(const Hopper& hopper, const HopperFootsteps& steps,
                                                   const Vec<4>& q_start, const Vec<4>& q_end, double T,
                                                   const HopperGaitShape& shape) {
  using namespace saltus::timefreezing;
  validate(hopper, steps, T, shape);
  std::vector<GaitPhase> phases;
  for (std::size_t k = 0; k <= steps.event_times.size(); ++k) {
    const double begin = k == 0 ? 0.0 : steps.event_times[k - 1];
    const double end = k == steps.event_times.size() ? T : steps.event_times[k];
    phases.push_back({begin, end, k % 2 == 0, static_cast<int>(k / 2)});
  }
  ScheduleGuess<Hopper> g;
  Mode<1> stick, open;
  stick[0] = ContactState::stick();
  for (const GaitPhase& p : phases) g.schedule.phases.push_back(p.stance ? stick : open);
  for (std::size_t k = 0; k + 1 < phases.size(); ++k)
    g.schedule.events.push_back(guards_between(hopper, g.schedule.phases[k], g.schedule.phases[k + 1]));
  g.event_times = steps.event_times;
  g.schedule = validated(hopper, g.schedule);
  const FootstepGait gait(hopper, steps, q_start, q_end, shape);
  g.state = [phases, gait](int k, double t) {
    const GaitPhase& p = phases[static_cast<std::size_t>(k)];
    const double c = std::clamp(t, p.begin, p.end), a = std::max(p.begin, c - 1e-5), b = std::min(p.end, c + 1e-5);
    VecT<double, 8> x;
    x << gait.pose(p, c), (gait.pose(p, b) - gait.pose(p, a)) / (b - a);
    return x;
  };
  g.input = [](double) { return VecT<double, 2>::Zero(); };
  return g;
}

HopperFootsteps footsteps_of(const Hopper& hopper, const timefreezing::ScheduleGuess<Hopper>& guess, const Vec<4>& q_start,
                             const Vec<4>& q_end, double T, double landing_stance) {
  const auto& phases = guess.schedule.phases;
  SALTUS_REQUIRE(!phases.empty() && phases.front()[0].closed(),
                 "footsteps_of: the schedule must start with the foot on the ground (closed), got ",
                 phases.empty() ? std::string("no phase") : describe(hopper, guess.schedule));
  SALTUS_REQUIRE(guess.event_times.size() + 1 == phases.size(), "footsteps_of: ", phases.size(), " phases need ",
                 phases.size() - 1, " event times, got ", guess.event_times.size());
  SALTUS_REQUIRE(std::isfinite(landing_stance) && landing_stance > 0.0, "footsteps_of: landing_stance must be > 0 [s], got ",
                 landing_stance);
  const auto begin = [&](std::size_t k) { return k == 0 ? 0.0 : guess.event_times[k - 1]; };
  const auto end = [&](std::size_t k) { return k + 1 == phases.size() ? T : guess.event_times[k]; };
  HopperFootsteps steps;
  for (std::size_t k = 0; k < phases.size();) {
    std::size_t last = k;  // the run of phases with the same contact status
    while (last + 1 < phases.size() && phases[last + 1][0].closed() == phases[k][0].closed()) ++last;
    if (phases[k][0].closed()) {
      const double t_mid = 0.5 * (begin(k) + end(last));
      std::size_t in = k;
      while (in < last && end(in) < t_mid) ++in;
      const VecT<double, 8> x = guess.state(static_cast<int>(in), t_mid);
      steps.footholds.push_back(hopper.foot<double>(VecT<double, 4>(x.head<4>()))[0]);
    }
    if (last + 1 < phases.size()) steps.event_times.push_back(end(last));
    k = last + 1;
  }
  if (!phases.back()[0].closed()) {  // ends in a flight: land for its last landing_stance seconds, at most half of it
    const double release = steps.event_times.back();
    steps.event_times.push_back(T - std::min(landing_stance, 0.5 * (T - release)));
    steps.footholds.push_back(0.0);
  }
  steps.footholds.front() = hopper.foot<double>(VecT<double, 4>(q_start))[0];
  steps.footholds.back() = hopper.foot<double>(VecT<double, 4>(q_end))[0];
  return steps;
}

}  // namespace saltus::scenes
