// Guards by kind: what can end a mode (thesis 2.42-2.53, A.1). The functions gamma themselves
// (their values from a state and its contact forces) are in dynamics/guards.hpp; this is the
// vocabulary the simulator, the trajectory and the analyses share.
//   touchdown   (open -> closed)    gamma = h_n(q)                                     state
//   release     (closed -> open)    gamma = lambda_n(x, u)                             state-input
//   stop        (slip -> stick)     gamma = zeta_t . d                                 state
//   slip onset  (stick -> slip)     gamma = mu^2 lambda_n^2 - ||lambda_t||^2            state-input
#pragma once

#include <array>
#include <cstdint>

namespace saltus {

enum class GuardKind : std::uint8_t { Touchdown, Release, Stop, SlipOnset };

inline const char* to_string(GuardKind k) {
  switch (k) {
    case GuardKind::Touchdown: return "touchdown";
    case GuardKind::Release: return "release";
    case GuardKind::Stop: return "stop";
    case GuardKind::SlipOnset: return "slip-onset";
  }
  return "?";
}

struct Guard {
  int contact = 0;
  GuardKind kind = GuardKind::Touchdown;
  bool operator==(const Guard&) const = default;
  /// Whether the guard's value depends on the input u (through the contact forces).
  bool depends_on_input() const { return kind == GuardKind::Release || kind == GuardKind::SlipOnset; }
};

/// The guards of a mode: at most two per contact.
template <int NC>
struct GuardList {
  std::array<Guard, 2 * NC + 1> items{};
  int count = 0;
  const Guard* begin() const { return items.data(); }
  const Guard* end() const { return items.data() + count; }
  const Guard& operator[](int k) const { return items[k]; }
  void push(Guard g) { items[count++] = g; }
};

}  // namespace saltus
