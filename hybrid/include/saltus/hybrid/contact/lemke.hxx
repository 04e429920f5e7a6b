// Definitions of lemke.hpp (the math and the interface are documented there).
//
// The library compiles these once for the bounds declared extern in lemke.hpp. Include this
// file, not lemke.hpp, to use another bound (the solvers are then instantiated on use), or to
// call the member template LemkeLcp::solve(options, score).
#pragma once

#include <saltus/hybrid/contact/lemke.hpp>

namespace saltus {

namespace detail {

// ---- LemkeLcp ---------------------------------------------------------------------------------

template <int MaxN>
ContactSolveStatus LemkeLcp<MaxN>::solve(const LemkeOptions& options) {
  return solve(options, [this](const Vector& x) { return residual(x); });
}

template <int MaxN>
template <class Score>
ContactSolveStatus LemkeLcp<MaxN>::solve(const LemkeOptions& options, Score&& score) {
  // tie factor, pivot factor, covering vector (0: ones)
  static constexpr std::array<std::array<double, 3>, 7> attempts{{{1.0, 1.0, 0},
                                                                  {1e-2, 1e2, 0},
                                                                  {1e2, 1e2, 0},
                                                                  {1e-4, 1e-2, 0},
                                                                  {1e2, 1e4, 0},
                                                                  {1.0, 1.0, 1},
                                                                  {1.0, 1.0, 2}}};
  int total = 0;
  ContactSolveStatus best = ContactSolveStatus::IterationLimit;
  double best_residual = 0.0;
  for (std::size_t a = 0; a < attempts.size(); ++a) {
    LemkeOptions o = options;
    o.tie_tolerance *= attempts[a][0];
    o.pivot_tolerance *= attempts[a][1];
    const ContactSolveStatus status = solve_once(o, static_cast<int>(attempts[a][2]));
    total += pivots;
    const double res = score(z);
    const bool solved = status == ContactSolveStatus::Solved;
    const bool best_solved = best == ContactSolveStatus::Solved;
    if (a == 0 || (solved && !best_solved) || (solved == best_solved && res < best_residual)) {
      best = status;
      best_residual = res;
      zbest_ = z;
    }
    if (best == ContactSolveStatus::Solved && best_residual <= options.retry_residual) break;
  }
  z = zbest_;
  pivots = total;
  return best;
}

template <int MaxN>
ContactSolveStatus LemkeLcp<MaxN>::solve_once(const LemkeOptions& options, int covering) {
  const int n = static_cast<int>(q.size());
  pivots = 0;
  z.setZero(n);
  if (n == 0 || q.minCoeff() >= 0.0) return ContactSolveStatus::Solved;
  const int max_pivots = options.max_pivots_per_variable * n;
  e_.resize(n);
  for (int i = 0; i < n; ++i)
    e_[i] = covering == 0 ? 1.0 : 1.0 + 0.5 * std::sin(1.7 * covering * (i + 1));

  // Variables: w_i = i, z_i = n + i, z0 = 2n. Initial basis: all w, B = I.
  const int z0 = 2 * n;
  Binv_.setIdentity(n, n);
  x_ = q;
  for (int i = 0; i < n; ++i) basis_[i] = i;

  // First pivot: z0 enters at the most negative q_i / e_i. Among ties the largest index is
  // the one that leaves every row of [q, B^{-1}] lexicographically positive.
  const double qmin = q.cwiseQuotient(e_).minCoeff();
  int r = 0;
  for (int i = 0; i < n; ++i)
    if (q[i] / e_[i] <= qmin + options.tie_tolerance * (1.0 + std::abs(qmin))) r = i;
  column(z0);
  pivot(r);
  int leaving = basis_[r];
  basis_[r] = z0;
  int entering = leaving + n;  // the complement of w_r

  ContactSolveStatus status = ContactSolveStatus::IterationLimit;
  while (pivots < max_pivots) {
    column(entering);
    r = ratio_test(z0, options);
    if (r < 0) {
      // A ray, unless z0 is basic at zero: the current almost-complementary point is then
      // complementary (a degenerate end that the ratio test missed by round-off).
      status = z0_value(z0) <= options.pivot_tolerance ? ContactSolveStatus::Solved
                                                       : ContactSolveStatus::NoSolution;
      break;
    }
    leaving = basis_[r];
    pivot(r);
    basis_[r] = entering;
    if (leaving == z0) {
      status = ContactSolveStatus::Solved;
      break;
    }
    entering = leaving < n ? leaving + n : leaving - n;
  }

  for (int i = 0; i < n; ++i)
    if (basis_[i] >= n && basis_[i] < 2 * n) z[basis_[i] - n] = x_[i];
  if (status == ContactSolveStatus::Solved) polish();
  return status;
}

template <int MaxN>
double LemkeLcp<MaxN>::residual(const Vector& x) {
  w_.noalias() = M * x;
  w_ += q;
  return w_.cwiseMin(x).cwiseAbs().maxCoeff();
}

template <int MaxN>
void LemkeLcp<MaxN>::column(int v) {
  const int n = static_cast<int>(q.size());
  if (v < n) {
    d_ = Binv_.col(v);
  } else if (v < 2 * n) {
    d_.noalias() = Binv_ * M.col(v - n);
    d_ = -d_;
  } else {
    d_.noalias() = Binv_ * e_;
    d_ = -d_;
  }
}

template <int MaxN>
double LemkeLcp<MaxN>::z0_value(int z0) const {
  for (int i = 0; i < static_cast<int>(q.size()); ++i)
    if (basis_[i] == z0) return x_[i];
  return 0.0;
}

template <int MaxN>
void LemkeLcp<MaxN>::pivot(int r) {
  ++pivots;
  const double inv = 1.0 / d_[r];
  Binv_.row(r) *= inv;
  x_[r] *= inv;
  prow_ = Binv_.row(r);
  d_[r] = 0.0;
  Binv_.noalias() -= d_ * prow_;
  x_ -= x_[r] * d_;
}

template <int MaxN>
int LemkeLcp<MaxN>::ratio_test(int z0, const LemkeOptions& options) {
  const int n = static_cast<int>(q.size());
  int count = 0;
  for (int i = 0; i < n; ++i)
    if (d_[i] > options.pivot_tolerance) cand_[count++] = i;
  if (count == 0) return -1;
  // Basic values are nonnegative in exact arithmetic; read a degenerate one that round-off
  // made -1e-17 as 0, lest it give the smallest (negative) ratio through a tiny d_i.
  auto entry = [&](int i, int c) { return c < 0 ? std::max(x_[i], 0.0) : Binv_(i, c); };
  for (int c = -1; c < n && count > 1; ++c) {
    double best = 0.0;
    for (int a = 0; a < count; ++a) {
      const int i = cand_[a];
      const double ratio = entry(i, c) / d_[i];
      if (a == 0 || ratio < best) best = ratio;
    }
    const double tol = options.tie_tolerance * (1.0 + std::abs(best));
    int kept = 0;
    for (int a = 0; a < count; ++a) {
      const int i = cand_[a];
      if (entry(i, c) / d_[i] <= best + tol) cand_[kept++] = i;
    }
    count = kept;
    if (c < 0)
      for (int a = 0; a < count; ++a)
        if (basis_[cand_[a]] == z0) return cand_[a];
  }
  return cand_[0];
}

template <int MaxN>
void LemkeLcp<MaxN>::polish() {
  const int n = static_cast<int>(q.size());
  int nz = 0;
  for (int i = 0; i < n; ++i)
    if (basis_[i] >= n && basis_[i] < 2 * n) cand_[nz++] = basis_[i] - n;
  if (solve_on(nz) && residual(zp_) <= residual(z)) z = zp_;
}

template <int MaxN>
bool LemkeLcp<MaxN>::solve_on(int nz) {
  const int n = static_cast<int>(q.size());
  zp_.setZero(n);
  if (nz == 0) return true;
  // M_ZZ is factorised in place in B^{-1}'s storage, no longer needed: a second n x n
  // matrix for an LU object would double the solver's size.
  rz_.resize(nz);
  for (int a = 0; a < nz; ++a) {
    for (int c = 0; c < nz; ++c) Binv_(a, c) = M(cand_[a], cand_[c]);
    rz_[a] = -q[cand_[a]];
  }
  if (!factorize(nz)) return false;
  sz_ = rz_;
  substitute(nz, sz_);
  for (int a = 0; a < nz; ++a) {  // one step of iterative refinement
    double s = -q[cand_[a]];
    for (int c = 0; c < nz; ++c) s -= M(cand_[a], cand_[c]) * sz_[c];
    rz_[a] = s;
  }
  substitute(nz, rz_);
  sz_ += rz_;
  if (!sz_.allFinite()) return false;
  // Values are nonnegative in exact arithmetic; a degenerate one can come out -1e-17.
  for (int a = 0; a < nz; ++a) zp_[cand_[a]] = std::max(sz_[a], 0.0);
  return true;
}

template <int MaxN>
bool LemkeLcp<MaxN>::factorize(int k) {
  for (int j = 0; j < k; ++j) {
    int pr = j;
    for (int i = j + 1; i < k; ++i)
      if (std::abs(Binv_(i, j)) > std::abs(Binv_(pr, j))) pr = i;
    perm_[j] = pr;
    if (!(std::abs(Binv_(pr, j)) > 0.0)) return false;
    if (pr != j) Binv_.row(j).head(k).swap(Binv_.row(pr).head(k));
    const double inv = 1.0 / Binv_(j, j);
    for (int i = j + 1; i < k; ++i) {
      const double l = Binv_(i, j) *= inv;
      for (int c = j + 1; c < k; ++c) Binv_(i, c) -= l * Binv_(j, c);
    }
  }
  return true;
}

template <int MaxN>
void LemkeLcp<MaxN>::substitute(int k, Vector& v) const {
  for (int j = 0; j < k; ++j) std::swap(v[j], v[perm_[j]]);
  for (int i = 0; i < k; ++i)
    for (int c = 0; c < i; ++c) v[i] -= Binv_(i, c) * v[c];
  for (int i = k - 1; i >= 0; --i) {
    for (int c = i + 1; c < k; ++c) v[i] -= Binv_(i, c) * v[c];
    v[i] /= Binv_(i, i);
  }
}

// ---- PolyhedralContactLcp ---------------------------------------------------------------------

template <int MaxContacts, int MaxDirections>
ContactSolveStatus PolyhedralContactLcp<MaxContacts, MaxDirections>::solve(
    const Problem& p, int spatial_directions, const LemkeOptions& options, Vector& lambda,
    double rotation, bool exact) {
  build(p, std::min(spatial_directions, MaxDirections), rotation);
  ContactSolveStatus status;
  if (exact) {
    status = lcp.solve(options, [&](const auto& z) {
      to_forces(z, p.rows(), lambda);
      y_.noalias() = p.A * lambda;
      y_ += p.b;
      return natural_map_residual(p, lambda, y_);
    });
  } else {
    status = lcp.solve(options);
  }
  to_forces(lcp.z, p.rows(), lambda);
  return status;
}

template <int MaxContacts, int MaxDirections>
void PolyhedralContactLcp<MaxContacts, MaxDirections>::build(const Problem& p,
                                                             int spatial_directions,
                                                             double rotation) {
  const double global = contact_problem_scale(p);  // m / trace(A)
  int n = 0;
  for (int k = 0; k < p.contacts; ++k) {
    const int r = p.row[k], nt = p.tangents[k], nk = 1 + nt;
    const double a = p.A.diagonal().segment(r, nk).cwiseAbs().sum() / nk;
    const double d = 1.0 / std::sqrt(a > 0.0 ? a : 1.0 / global);
    const int dirs = nt == 0 || !(p.mu[k] > 0.0) ? 0 : nt == 1 ? 2 : spatial_directions;
    first_[k] = n;
    dirs_[k] = dirs;
    set(n++, r, d, r, 0.0);
    for (int i = 0; i < dirs; ++i) {
      if (nt == 1) {
        set(n++, r + 1, i == 0 ? d : -d, r + 1, 0.0);
      } else {
        const double th = rotation + 2.0 * 3.14159265358979323846 * i / dirs;
        set(n++, r + 1, d * std::cos(th), r + 2, d * std::sin(th));
      }
    }
    if (dirs > 0) set(n++, r, 0.0, r, 0.0);  // beta, the slip speed: no part of lambda
  }
  lcp.M.resize(n, n);
  lcp.q.resize(n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      double v = 0.0;
      for (int a = 0; a < 2; ++a)
        for (int c = 0; c < 2; ++c) v += coef_[i][a] * coef_[j][c] * p.A(row_[i][a], row_[j][c]);
      lcp.M(i, j) = v;
    }
    lcp.q[i] = coef_[i][0] * p.b[row_[i][0]] + coef_[i][1] * p.b[row_[i][1]];
  }
  for (int k = 0; k < p.contacts; ++k) {
    const int dirs = dirs_[k];
    if (dirs == 0) continue;
    const int normal = first_[k], slip = normal + dirs + 1;
    lcp.M(slip, normal) = p.mu[k];
    for (int i = 1; i <= dirs; ++i) {
      lcp.M(normal + i, slip) = 1.0;
      lcp.M(slip, normal + i) = -1.0;
    }
  }
  qscale_ = lcp.q.cwiseAbs().maxCoeff();
  if (!(qscale_ > 0.0)) qscale_ = 1.0;
  lcp.q /= qscale_;
}

template <int MaxContacts, int MaxDirections>
template <class Z>
void PolyhedralContactLcp<MaxContacts, MaxDirections>::to_forces(const Z& z, int m,
                                                                 Vector& lambda) const {
  lambda.setZero(m);
  for (int j = 0; j < static_cast<int>(z.size()); ++j)
    for (int a = 0; a < 2; ++a) lambda[row_[j][a]] += qscale_ * coef_[j][a] * z[j];
}

}  // namespace detail

// ---- LemkeSolver ------------------------------------------------------------------------------

template <int MaxContacts>
ContactSolveStatus LemkeSolver<MaxContacts>::solve(const Problem& p, Solution& out) {
  validate(p);
  const int m = p.rows();
  out.lambda.setZero(m);
  out.iterations = 0;
  out.status = ContactSolveStatus::Solved;

  // lambda = 0 solves the problem as soon as no contact is approaching: the friction radius
  // mu lambda_n is then 0, whatever the tangential velocity (a wider test than q >= 0, which
  // would also demand b_t = 0).
  bool trivial = true;
  for (int k = 0; k < p.contacts; ++k) trivial = trivial && p.b[p.row[k]] >= 0.0;
  if (trivial) {
    out.y = p.b;
    out.residual = natural_map_residual(p, out.lambda, out.y);
    return out.status;
  }

  out.status = lcp_.solve(p, 2, options, out.lambda, 0.0, true);
  out.iterations = lcp_.lcp.pivots;
  out.y.noalias() = p.A * out.lambda;
  out.y += p.b;
  out.residual = natural_map_residual(p, out.lambda, out.y);
  return out.status;
}

template <int MaxContacts>
void LemkeSolver<MaxContacts>::validate(const Problem& p) {
  SALTUS_REQUIRE(p.contacts >= 0 && p.contacts <= MaxContacts, 
                "LemkeSolver: ", p.contacts, " contacts, at most ", MaxContacts);
  for (int k = 0; k < p.contacts; ++k) {
    SALTUS_REQUIRE(p.tangents[k] >= 0 && p.tangents[k] <= 1, 
                  "LemkeSolver: contact ", k, " has ", p.tangents[k],
                  " tangents; Lemke solves planar problems only (0 or 1 tangent), use "
                  "CoulombSolver for spatial friction");
    SALTUS_REQUIRE(std::isfinite(p.mu[k]) && p.mu[k] >= 0.0, 
                  "LemkeSolver: contact ", k, " has friction coefficient mu = ", p.mu[k]);
  }
  const int m = p.rows();
  SALTUS_REQUIRE(p.A.rows() == m && p.A.cols() == m && p.b.size() == m, 
                "LemkeSolver: A is ", p.A.rows(), "x", p.A.cols(), " and b has ", p.b.size(),
                " rows, the contacts declare ", m);
  SALTUS_REQUIRE(p.A.allFinite() && p.b.allFinite(), 
                "LemkeSolver: A or b is not finite");
}

}  // namespace saltus
