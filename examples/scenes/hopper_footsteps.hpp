// The hopper's footsteps: a schedule of sticking stances and flights, and a kinematically
// consistent guess of the motion in it, for the mode-schedule refinement of the hopper over three
// holes (timefreezing/refinement/refinement.hpp; docs/refinement.md, "Hopper over three holes").
//
// The guess (footstep_guess): in a stance the foot stays on its foothold while the hip moves at
// constant speed from `hip_offset` behind it to `hip_offset` ahead of it, the hip-to-foot distance
// `stance_leg` (the knee bent forward, the angles by inverse kinematics); the first stance starts
// at the start pose and the last one ends at the end pose, the leg length going linearly from and
// to theirs. In a flight the hip moves at constant speed from the lift-off pose to the next
// touchdown pose on a ballistic arc (capped at z = 0.54, below the path row z <= 0.55) and the
// joint angles go linearly between the two poses. Velocities by central differences over 1e-5 s,
// zero torques. It says where the feet go and when, not how the leg pushes: the refinement finds
// that.
#pragma once

#include "scenes/hopper.hpp"

#include <saltus/timefreezing/refinement/schedule_guess.hpp>

#include <vector>

namespace saltus::scenes {

/// Stances on `footholds` alternating with flights, from a stance to a stance.
struct HopperFootsteps {
  std::vector<double> footholds;    ///< the foot's x in each stance [m], at least one
  std::vector<double> event_times;  ///< release, touchdown, release, ... [s]: 2 (stances - 1), increasing
};

/// The shape of the guessed stances (file comment) [m].
struct HopperGaitShape {
  double hip_offset = 0.15;  ///< hip behind the foothold at touchdown, ahead of it at lift-off
  double stance_leg = 0.39;  ///< hip-to-foot distance in a stance (< thigh + shank = 0.4)
};

/// The schedule of `steps` (each stance a sticking foot, each flight open, touchdowns plastic as
/// the scene's restitution says) and the guess of the motion in it (file comment), over [0, T],
/// from the pose q_start at t = 0 to q_end at t = T. Preconditions, not checked: q_start's and
/// q_end's feet stand on the first and the last foothold (the guess takes their hip positions and
/// leg lengths; its joint angles come from inverse kinematics, not from q_start and q_end).
/// Throws InvalidArgument for no foothold, a count of event times other than 2 (stances - 1),
/// event times not strictly increasing inside (0, T), a foothold or T that is not finite, T <= 0,
/// or a shape whose leg does not fit the hopper (stance_leg outside (0, thigh + shank), hip_offset
/// outside [0, stance_leg)).
timefreezing::ScheduleGuess<Hopper> footstep_guess(const Hopper& hopper, const HopperFootsteps& steps,
                                                   const Vec<4>& q_start, const Vec<4>& q_end, double T,
                                                   const HopperGaitShape& shape = {});

/// The footsteps of a discovered schedule (discover_schedule's guess, or any ScheduleGuess of the
/// hopper): consecutive phases with the foot closed (stick or slip) are one stance, open phases
/// one flight; a stance's foothold is the foot's x at the middle of its time in the guess's
/// motion, except the first and the last, which stand where q_start's and q_end's feet stand (the
/// foot is on the ground at the start and at the end). A schedule that ends in a flight, as a
/// relaxed motion whose foot reaches the ground only at T does, lands for the last
/// `landing_stance` seconds of it [s, > 0], or for its second half when it is shorter than twice
/// that (the hopper's discovery from hop_guess ends in a flight of 38 ms). Throws InvalidArgument
/// when the schedule does not start with the foot closed, when the count of
/// event times does not match the phases, or for landing_stance <= 0; their order and T are not
/// checked here (footstep_guess checks the footsteps it is given).
HopperFootsteps footsteps_of(const Hopper& hopper, const timefreezing::ScheduleGuess<Hopper>& guess, const Vec<4>& q_start,
                             const Vec<4>& q_end, double T, double landing_stance = 0.1);

}  // namespace saltus::scenes
