// Contact modes. A contact is open, sticking or slipping; a mode of the system is the vector of
// contact modes (thesis 2.3.2: the sets I_op, I_st, I_sl). Any mix is allowed: the thesis'
// simplifying assumption that all closed contacts share one mode (E.6) is not needed here.
#pragma once

#include <saltus/hybrid/vocabulary/scene.hpp>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <sstream>
#include <string>

namespace saltus {

enum class ContactMode : std::uint8_t { Open, Stick, Slip };

inline const char* to_string(ContactMode m) {
  switch (m) {
    case ContactMode::Open: return "open";
    case ContactMode::Stick: return "stick";
    case ContactMode::Slip: return "slip";
  }
  return "?";
}

/// The mode of one contact. For slip, `slip_direction` is a unit vector in the contact's tangent
/// coordinates:
///  - planar contacts: (+1, 0) or (-1, 0), the sign of zeta_t the slip keeps. The flow uses this
///    sign (not the current sign of zeta_t), so the slip flow is smooth and can be continued past
///    zeta_t = 0, which reference spreading and the slip->stick guard s * zeta_t rely on;
///  - spatial contacts: the direction of zeta_t when the slip phase was last refreshed. The flow
///    uses the current direction zeta_t / ||zeta_t|| (thesis A.23-A.24); the stored direction only
///    orients the slip->stick guard zeta_t . d, whose zero is the stop of the slip.
struct ContactState {
  ContactMode mode = ContactMode::Open;
  Eigen::Vector2d slip_direction = Eigen::Vector2d::Zero();

  bool closed() const { return mode != ContactMode::Open; }
  static ContactState open() { return {}; }
  static ContactState stick() { return {ContactMode::Stick, Eigen::Vector2d::Zero()}; }
  static ContactState slip(const Eigen::Vector2d& direction) { return {ContactMode::Slip, direction}; }
  static ContactState slip_planar(int sign) { return {ContactMode::Slip, Eigen::Vector2d(sign >= 0 ? 1.0 : -1.0, 0.0)}; }

  bool operator==(const ContactState& o) const {
    return mode == o.mode && (mode != ContactMode::Slip || slip_direction == o.slip_direction);
  }
};

template <int NC>
struct Mode {
  std::array<ContactState, NC> contacts{};

  ContactState& operator[](int i) { return contacts[i]; }
  const ContactState& operator[](int i) const { return contacts[i]; }
  bool operator==(const Mode& o) const { return contacts == o.contacts; }

  static Mode all_open() { return Mode{}; }
  int closed_count() const {
    int n = 0;
    for (const auto& c : contacts) n += c.closed();
    return n;
  }
};

/// "C_L:slip+ C_R:stick" — names from the scene, planar slip with its sign, spatial with its
/// direction.
template <Scene S>
std::string describe(const S& scene, const Mode<S::nc>& mode) {
  std::ostringstream os;
  os.precision(3);
  for (int i = 0; i < S::nc; ++i) {
    if (i) os << ' ';
    // A closed frictionless contact is stored as Slip (its flow has no tangential rows) but it is
    // neither sliding nor sticking: it is reported as "closed".
    const bool frictionless = scene.contact(i).tangents() == 0;
    os << scene.contact(i).name << ':' << (frictionless && mode[i].closed() ? "closed" : to_string(mode[i].mode));
    if (mode[i].mode == ContactMode::Slip && !frictionless) {
      if (scene.contact(i).tangents() == 1)
        os << (mode[i].slip_direction[0] > 0 ? '+' : '-');
      else if (scene.contact(i).tangents() == 2)
        os << '(' << mode[i].slip_direction[0] << ',' << mode[i].slip_direction[1] << ')';
    }
  }
  return os.str();
}

}  // namespace saltus
