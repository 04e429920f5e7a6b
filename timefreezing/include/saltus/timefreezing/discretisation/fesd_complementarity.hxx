// FesdMpcc: the complementarity pairs (fesd.hpp); every side is affine in x.
//
// STAGE-WISE PAIRS (the fixed grid; with switch detection, the switching functions that have no
// cross-complementarity): per stage point r and switching function m,
//     0 <= lambda_n,r,m _|_ alpha_r,m >= 0,     0 <= lambda_p,r,m _|_ 1 - alpha_r,m >= 0.
// With c = lambda_p - lambda_n given, their equalities lambda_n alpha = sigma and
// lambda_p (1 - alpha) = sigma determine alpha, so they are marked smoothable
// (MpccSolverOptions::Relaxation::Smoothing).
// CROSS-COMPLEMENTARITY (switch detection; the FESD paper's cross-complementarity in NOSNOC's
// FE_STAGE form): for each element, each switching function m and each point p among the element's
// stages AND the previous element's end point,
//     0 <= lambda_n,p,m  _|_  sum_r alpha_r,m >= 0,     0 <= lambda_p,p,m  _|_  sum_r (1 - alpha_r,m) >= 0.
// Since every term is nonnegative, this is equivalent to lambda_n,p alpha_r = 0 for every pair of
// points: inside one element the active set cannot change, so a switch can only happen at an
// element boundary, where the free h puts it. Which functions get it: options.switching (gaps
// always; velocities with velocity_detection). Frictionless contacts fix alpha_3 = 1 and
// lambda_n,3 = 0 by bounds and have no tangential pairs.
#pragma once

#include <saltus/timefreezing/discretisation/fesd.hpp>

#include <string>
#include <utility>
#include <vector>

namespace saltus::timefreezing {

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::build_pairs() {
  pairs_.clear();
  for (int k = 0; k < options_.grid.control_intervals; ++k)
    for (int j = 0; j < options_.grid.finite_elements; ++j)
      for (int m = 0; m < nsw; ++m) {
        if (!switching_active(m)) continue;
        if (cross_complementary(m)) cross_pairs(k, j, m);
        else stagewise_pairs(k, j, m);
      }
}

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::stagewise_pairs(int k, int j, int m) {
  const std::string el = "[" + std::to_string(k) + "," + std::to_string(j) + "]", sw = "[" + std::to_string(m) + "]";
  for (int r = 0; r < options_.grid.stages; ++r) {
    const int a = alpha_index(k, j, r) + m;
    const std::string at = el + "[stage " + std::to_string(r) + "]" + sw;
    pairs_.push_back({{{{lambda_n_index(k, j, r) + m, 1.0}}, 0.0}, {{{a, 1.0}}, 0.0}, "lambda_n" + at + " _|_ alpha", true});
    pairs_.push_back(
        {{{{lambda_p_index(k, j, r) + m, 1.0}}, 0.0}, {{{a, -1.0}}, 1.0}, "lambda_p" + at + " _|_ 1 - alpha", true});
  }
}

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::cross_pairs(int k, int j, int m) {
  const int ns = options_.grid.stages;
  const std::string el = "[" + std::to_string(k) + "," + std::to_string(j) + "]", sw = "[" + std::to_string(m) + "]";
  AffineExpression sum_alpha, sum_one_minus;
  for (int r = 0; r < ns; ++r) {
    sum_alpha.terms.push_back({alpha_index(k, j, r) + m, 1.0});
    sum_one_minus.terms.push_back({alpha_index(k, j, r) + m, -1.0});
  }
  sum_one_minus.constant = ns;
  // Points: the previous element's end (when there is one), then this element's stages; each given
  // by its stage base index (where its Y starts).
  std::vector<std::pair<int, std::string>> points;
  const int ys = start_state_index(k, j);
  if (ys >= 0) points.push_back({ys, "start"});
  for (int r = 0; r < ns; ++r) points.push_back({stage_index(k, j, r), "stage " + std::to_string(r)});
  for (const auto& [base, label] : points) {
    const std::string at = el + "[" + label + "]" + sw;
    pairs_.push_back({{{{base + 2 * ny + 2 * nsw + m, 1.0}}, 0.0}, sum_alpha, "lambda_n" + at + " _|_ sum alpha"});
    pairs_.push_back({{{{base + 2 * ny + nsw + m, 1.0}}, 0.0}, sum_one_minus, "lambda_p" + at + " _|_ sum (1 - alpha)"});
  }
}

template <Scene S, class Ocp>
const std::vector<ComplementarityPair>& FesdMpcc<S, Ocp>::complementarity_pairs() const {
  return pairs_;
}

}  // namespace saltus::timefreezing
