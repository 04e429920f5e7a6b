// The mode schedule of a hybrid motion: the sequence of its phases, each a mode of the scene (per
// contact: open, stick, slip+ or slip-; any mix), and between two phases the event that ends the
// first, with every guard that fires there (thesis 2.42-2.53: touchdown h_n = 0, release
// lambda_n = 0, stop zeta_t = 0, slip onset |lambda_t| = mu lambda_n). A simultaneous event
// lists all its guards (the plank-box's flat landing: the touchdowns of both corners).
//
// A schedule is what the relaxed time-freezing homotopy DISCOVERS (extraction.hpp) and what the
// refinement (refinement.hpp) keeps FIXED while it optimises the phase durations, the states and
// the inputs of a smooth multi-phase OCP.
//
// Consistency of one event between the modes A (before) and B (after), contact by contact:
//   A open,   B closed                 a touchdown of the contact;
//   A closed, B open                   a release of the contact, or an impact of another contact
//                                      at the same event that throws it off (no guard of its own);
//   A slip,   B stick (or slip of the  a stop of the contact (planar slip reversal: the tangential
//             opposite sign)           velocity passes zero), or an impact at the same event;
//   A stick,  B slip                   a slip onset of the contact, or an impact at the event;
//   A open,   B open                   nothing, or a touchdown when the contact is elastic (e_n > 0:
//                                      a bounce);
//   A == B (closed)                    nothing (an impact at the event still involves it).
// And every guard must be able to fire between A and B (a touchdown needs the contact open in A,
// a release closed in A and open in B, a stop slip in A, a slip onset stick in A and slip in B).
// An event with a touchdown is an impact: the jump map of its impulse mode (impulse_mode_at)
// takes x- to x+.
#pragma once

#include <saltus/hybrid/vocabulary/errors.hpp>
#include <saltus/hybrid/vocabulary/guard.hpp>
#include <saltus/hybrid/vocabulary/impact_mode.hpp>
#include <saltus/hybrid/vocabulary/mode.hpp>
#include <saltus/hybrid/vocabulary/scene.hpp>

#include <algorithm>
#include <string>
#include <vector>

namespace saltus::timefreezing {

/// The end of one phase: every guard that fires there.
struct ScheduleEvent {
  std::vector<Guard> guards;

  bool impact() const {
    return std::any_of(guards.begin(), guards.end(), [](const Guard& g) { return g.kind == GuardKind::Touchdown; });
  }
  bool has(int contact, GuardKind kind) const {
    return std::any_of(guards.begin(), guards.end(),
                       [&](const Guard& g) { return g.contact == contact && g.kind == kind; });
  }
};

/// Phases (at least one) and the events between them (phases.size() - 1).
template <int NC>
struct ModeSchedule {
  std::vector<Mode<NC>> phases;
  std::vector<ScheduleEvent> events;

  int phase_count() const { return static_cast<int>(phases.size()); }
};

/// "C_L:slip+ C_R:slip+" style name of phase k, "touchdown C_L + touchdown C_R" of event k.
template <Scene S>
std::string describe_event(const S& scene, const ScheduleEvent& event) {
  std::string s;
  for (const Guard& g : event.guards) {
    if (!s.empty()) s += " + ";
    s += std::string(to_string(g.kind)) + " " + scene.contact(g.contact).name;
  }
  return s.empty() ? std::string("(no guard)") : s;
}

/// "flight [touchdown C_L + touchdown C_R] C_L:slip+ C_R:slip+ [...] ...": the whole schedule on one line.
template <Scene S>
std::string describe(const S& scene, const ModeSchedule<S::nc>& schedule) {
  std::string s;
  for (int k = 0; k < schedule.phase_count(); ++k) {
    if (k > 0) s += " [" + describe_event(scene, schedule.events[static_cast<std::size_t>(k - 1)]) + "] ";
    s += describe(scene, schedule.phases[static_cast<std::size_t>(k)]);
  }
  return s;
}

/// The mode of a contact as a schedule stores it: a closed frictionless contact is slip with the
/// zero direction (as the simulator stores it), a planar slip direction is (+-1, 0).
template <Scene S>
ContactState normalised_contact_state(const S& scene, int i, const ContactState& c) {
  if (!c.closed()) return ContactState::open();
  const int nt = scene.contact(i).tangents();
  if (nt == 0) return ContactState::slip(Eigen::Vector2d::Zero());
  if (c.mode == ContactMode::Stick) return ContactState::stick();
  if (nt == 1) return ContactState::slip_planar(c.slip_direction[0] >= 0 ? 1 : -1);
  return c;
}

/// The guards that a change of mode from `before` to `after` needs (the canonical event between
/// two modes, without impacts of other contacts): touchdown, release, stop (slip to stick or slip
/// reversal), slip onset.
template <Scene S>
ScheduleEvent guards_between(const S& scene, const Mode<S::nc>& before, const Mode<S::nc>& after) {
  ScheduleEvent e;
  for (int i = 0; i < S::nc; ++i) {
    const ContactState a = normalised_contact_state(scene, i, before[i]), b = normalised_contact_state(scene, i, after[i]);
    if (a == b) continue;
    if (!a.closed() && b.closed()) e.guards.push_back({i, GuardKind::Touchdown});
    else if (a.closed() && !b.closed()) e.guards.push_back({i, GuardKind::Release});
    else if (a.mode == ContactMode::Slip) e.guards.push_back({i, GuardKind::Stop});
    else e.guards.push_back({i, GuardKind::SlipOnset});
  }
  return e;
}

/// The impulse mode of event k (an impact, ScheduleEvent::impact): every contact closed in the
/// phase after it takes part, sticking or slipping as that phase says (the post-impact mode is the
/// next phase's mode, thesis A.34-A.47); the others take no impulse.
template <Scene S>
ImpactMode<S::nc> impulse_mode_after(const S& scene, const Mode<S::nc>& after) {
  ImpactMode<S::nc> m;
  for (int i = 0; i < S::nc; ++i) {
    const ContactState c = normalised_contact_state(scene, i, after[i]);
    if (!c.closed()) continue;
    m[i].role = c.mode == ContactMode::Stick ? ImpulseRole::Stick : ImpulseRole::Slip;
    m[i].slip_direction = c.slip_direction;
  }
  return m;
}

/// Throws InvalidArgument naming the event (or phase) and the condition when `schedule` is not a
/// schedule of `scene`: no phase, an event count other than phases - 1, an event without guards,
/// a guard on a contact index out of range, a guard that cannot fire between the modes around it
/// (a touchdown of a contact that is already closed, ...), a change of a contact's mode that no
/// guard and no impact explains, a spatial-friction contact (not supported by the refinement), a
/// planar slip without a direction. Returns the schedule with normalised modes
/// (normalised_contact_state).
template <Scene S>
ModeSchedule<S::nc> validated(const S& scene, ModeSchedule<S::nc> schedule);

}  // namespace saltus::timefreezing

#include <saltus/timefreezing/refinement/mode_schedule.hxx>
