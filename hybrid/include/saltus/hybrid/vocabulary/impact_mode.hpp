// Impact modes: which contacts take an impulse at an impact, and how (sticking, or slipping along
// a post-impact direction). The solution of the impact problem (dynamics/impact.hpp) fixes one;
// the jump map of that mode (dynamics/jump_map.hpp) is then a smooth function of x-.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>

namespace saltus {

/// How a contact takes part in an impulse.
enum class ImpulseRole : std::uint8_t { None, Stick, Slip };

inline const char* to_string(ImpulseRole r) {
  switch (r) {
    case ImpulseRole::None: return "none";
    case ImpulseRole::Stick: return "stick";
    case ImpulseRole::Slip: return "slip";
  }
  return "?";
}

struct ImpulseMode {
  ImpulseRole role = ImpulseRole::None;
  /// Slip: unit direction of the post-impact tangential velocity (planar: (+-1, 0)).
  Eigen::Vector2d slip_direction = Eigen::Vector2d::Zero();
  bool operator==(const ImpulseMode& o) const {
    return role == o.role && (role != ImpulseRole::Slip || slip_direction == o.slip_direction);
  }
};

template <int NC>
struct ImpactMode {
  std::array<ImpulseMode, NC> contacts{};
  ImpulseMode& operator[](int i) { return contacts[i]; }
  const ImpulseMode& operator[](int i) const { return contacts[i]; }
  bool operator==(const ImpactMode& o) const { return contacts == o.contacts; }
  bool any() const {
    for (const auto& c : contacts)
      if (c.role != ImpulseRole::None) return true;
    return false;
  }
};

}  // namespace saltus
