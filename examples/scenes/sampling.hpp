// Random pre-impact states of a scene, shared by the tests and the benchmarks: a configuration
// where at least one contact touches (scene.touching_configuration, which includes the redundant
// cases such as a box flat on its face) and a random velocity under which at least one touching
// contact approaches.
#pragma once

#include <saltus/hybrid/dynamics/kinematics.hpp>

#include <random>

namespace saltus::scenes {

template <Scene S, class Rng>
Vec<2 * S::nq> random_pre_impact_state(const S& scene, Rng& rng, double speed = 2.0) {
  constexpr int nq = S::nq;
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const Vec<nq> q = scene.touching_configuration(rng);
  Vec<nq> v;
  for (int k = 0; k < nq; ++k) v[k] = speed * unit(rng);
  Kinematics<S> kin;
  evaluate_kinematics(scene, q, v, kin);
  double most_approaching = 0.0;
  for (int i = 0; i < S::nc; ++i)
    if (kin.contacts[i].gap <= 1e-12) most_approaching = std::min(most_approaching, kin.contacts[i].zeta_n);
  if (most_approaching >= 0.0) v = -v;  // flipping v flips every normal velocity
  Vec<2 * nq> x;
  x.template head<nq>() = q;
  x.template tail<nq>() = v;
  return x;
}

}  // namespace saltus::scenes
