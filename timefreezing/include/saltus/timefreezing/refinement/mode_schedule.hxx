// Definitions of mode_schedule.hpp (cheap: included by it).
#pragma once

#include <saltus/timefreezing/refinement/mode_schedule.hpp>

namespace saltus::timefreezing {

namespace detail {

template <Scene S>
std::string contact_change_problem(const S& scene, const ContactState& a, const ContactState& b,
                                   const ScheduleEvent& e, int i) {
  const std::string name = scene.contact(i).name;
  const bool impact = e.impact();
  for (const Guard& g : e.guards) {
    if (g.contact != i) continue;
    const std::string guard = std::string(to_string(g.kind)) + " " + name;
    switch (g.kind) {
      case GuardKind::Touchdown:
        if (a.closed()) return "guard '" + guard + "' cannot fire: the contact is already closed before it";
        if (!b.closed() && scene.contact(i).restitution == 0.0)
          return "guard '" + guard + "' leaves the contact open after it, which needs restitution e_n > 0";
        break;
      case GuardKind::Release:
        if (!a.closed()) return "guard '" + guard + "' cannot fire: the contact is open before it";
        if (b.closed()) return "guard '" + guard + "' leaves the contact closed after it";
        break;
      case GuardKind::Stop:
        if (a.mode != ContactMode::Slip || scene.contact(i).tangents() == 0)
          return "guard '" + guard + "' cannot fire: the contact does not slip before it";
        if (!b.closed() || b == a) return "guard '" + guard + "' needs the contact to stick or reverse its slip after it";
        break;
      case GuardKind::SlipOnset:
        if (a.mode != ContactMode::Stick) return "guard '" + guard + "' cannot fire: the contact does not stick before it";
        if (b.mode != ContactMode::Slip) return "guard '" + guard + "' needs the contact to slip after it";
        break;
    }
  }
  if (a == b) return "";
  const bool open_to_closed = !a.closed() && b.closed(), closed_to_open = a.closed() && !b.closed();
  if (open_to_closed && !e.has(i, GuardKind::Touchdown)) return "contact " + name + " closes without its touchdown guard";
  if (closed_to_open && !e.has(i, GuardKind::Release) && !impact)
    return "contact " + name + " opens without its release guard or an impact";
  if (a.closed() && b.closed() && !impact) {
    if (a.mode == ContactMode::Slip && !e.has(i, GuardKind::Stop))
      return "contact " + name + " stops slipping without its stop guard or an impact";
    if (a.mode == ContactMode::Stick && !e.has(i, GuardKind::SlipOnset))
      return "contact " + name + " starts slipping without its slip-onset guard or an impact";
  }
  return "";
}

}  // namespace detail

template <Scene S>
ModeSchedule<S::nc> validated(const S& scene, ModeSchedule<S::nc> schedule) {
  constexpr int nc = S::nc;
  SALTUS_REQUIRE(!schedule.phases.empty(), "mode schedule: it has no phase");
  SALTUS_REQUIRE(schedule.events.size() + 1 == schedule.phases.size(), "mode schedule: ", schedule.phases.size(),
                 " phases need ", schedule.phases.size() - 1, " events, got ", schedule.events.size());
  for (int i = 0; i < nc; ++i)
    SALTUS_REQUIRE(scene.contact(i).friction != Friction::Spatial, "mode schedule: contact '", scene.contact(i).name,
                   "' has spatial friction, which the refinement does not support (planar and frictionless only)");
  for (std::size_t k = 0; k < schedule.phases.size(); ++k)
    for (int i = 0; i < nc; ++i) {
      const ContactState& c = schedule.phases[k][i];
      SALTUS_REQUIRE(c.mode != ContactMode::Slip || scene.contact(i).tangents() == 0 || c.slip_direction[0] != 0.0,
                     "mode schedule: phase ", k, ": contact '", scene.contact(i).name, "' slips without a direction");
      schedule.phases[k][i] = normalised_contact_state(scene, i, c);
    }
  for (std::size_t k = 0; k < schedule.events.size(); ++k) {
    const ScheduleEvent& e = schedule.events[k];
    SALTUS_REQUIRE(!e.guards.empty(), "mode schedule: event ", k, " (between phases ", k, " and ", k + 1,
                   ") has no guard");
    for (const Guard& g : e.guards)
      SALTUS_REQUIRE(g.contact >= 0 && g.contact < nc, "mode schedule: event ", k, ": guard on contact ", g.contact,
                     " of ", nc);
    for (int i = 0; i < nc; ++i) {
      const std::string problem =
          detail::contact_change_problem(scene, schedule.phases[k][i], schedule.phases[k + 1][i], e, i);
      SALTUS_REQUIRE(problem.empty(), "mode schedule: event ", k, " (", describe_event(scene, e), ", between '",
                     describe(scene, schedule.phases[k]), "' and '", describe(scene, schedule.phases[k + 1]),
                     "'): ", problem);
    }
  }
  return schedule;
}

}  // namespace saltus::timefreezing
