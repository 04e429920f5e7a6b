// The force (or impulse) of one contact: normal component and up to two tangential components in
// the contact's tangent coordinates (thesis 2.4-2.6). T is double, or a dual number when
// derivatives are carried.
#pragma once

#include <saltus/hybrid/vocabulary/scene.hpp>

namespace saltus {

/// Contact force or impulse: `normal` (N, or N s), `tangent` (first `tangents()` entries used).
template <class T>
struct ContactForce {
  T normal{};
  VecT<T, 2> tangent = VecT<T, 2>::Zero();
};

}  // namespace saltus
