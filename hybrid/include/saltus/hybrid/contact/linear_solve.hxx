// Definitions of MinNormSolver (linear_solve.hpp). The library compiles them once for the
// bounds declared extern there (hybrid/src/linear_solve_*.cpp); include this file, not
// linear_solve.hpp, to use another bound (then instantiated on use).
#pragma once

#include <saltus/hybrid/contact/linear_solve.hpp>

namespace saltus {

template <int MaxN>
MinNormSolver<MaxN>::MinNormSolver() : cod_(MaxN, MaxN) {
  cod_.setThreshold(delassus_rank_threshold);
  A_.resize(MaxN, MaxN);
  tmp_.resize(MaxN);
  work_.resize(MaxN);
}

template <int MaxN>
typename MinNormSolver<MaxN>::Matrix& MinNormSolver<MaxN>::matrix(int m) {
  SALTUS_INVARIANT(m <= MaxN, "a minimum-norm solve is sized within its bound");
  A_.resize(m, m);
  return A_;
}

template <int MaxN>
void MinNormSolver<MaxN>::factorize() {
  cod_.compute(A_);
}

template <int MaxN>
void MinNormSolver<MaxN>::solve_in_place(Vector& b) const {
  min_norm_solve(cod_, b, tmp_, work_);
  b = tmp_;
}

template <int MaxN>
int MinNormSolver<MaxN>::rank() const {
  return static_cast<int>(cod_.rank());
}

template <int MaxN>
void MinNormSolver<MaxN>::set_threshold(double relative) {
  cod_.setThreshold(relative);
}

}  // namespace saltus
