// Dense output of a smooth segment: a chain of polynomial pieces, one per integrator step.
// Every backend writes the same representation,
//     x(t) = sum_{j=0..degree} c_j theta^j,   theta = (t - t_ref) / h,
// so that a trajectory evaluates the same way whichever integrator produced it:
//  - Dormand-Prince (odeint): the quartic through x0, x1, x0', x1' and the integrator's own
//    continuous extension at the step's midpoint, t_ref = t0, h = t1 - t0 (4th order, like the
//    method's continuous extension);
//  - CVODE: the Nordsieck history at the end of the step, c_j = h^j x^(j)(t_n) / j!, t_ref = t_n
//    (order q of the step).
#pragma once

#include <saltus/hybrid/vocabulary/errors.hpp>
#include <saltus/hybrid/vocabulary/scene.hpp>

#include <algorithm>
#include <vector>

namespace saltus {

template <int N>
struct PolynomialPiece {
  static constexpr int max_degree = 5;
  double t0 = 0, t1 = 0;       ///< validity interval (t0 < t1, or t1 < t0 for backward pieces)
  double t_ref = 0, h = 1;     ///< theta = (t - t_ref) / h
  int degree = 0;
  Eigen::Matrix<double, N, max_degree + 1> c;

  PolynomialPiece() { c.setZero(); }

  Vec<N> value(double t) const {
    const double th = (t - t_ref) / h;
    Vec<N> x = c.col(degree);
    for (int j = degree - 1; j >= 0; --j) x = x * th + c.col(j);
    return x;
  }
  Vec<N> derivative(double t) const {
    const double th = (t - t_ref) / h;
    Vec<N> d = Vec<N>::Zero();
    for (int j = degree; j >= 1; --j) d = d * th + double(j) * c.col(j);
    return d / h;
  }
  double lo() const { return std::min(t0, t1); }
  double hi() const { return std::max(t0, t1); }
};

/// The quartic through (x0, x1, f0, f1) at theta = 0, 1 and xm at theta = 1/2 on [t0, t1].
template <int N>
PolynomialPiece<N> quartic_piece(double t0, double t1, const Vec<N>& x0, const Vec<N>& x1, const Vec<N>& f0,
                                 const Vec<N>& f1, const Vec<N>& xm) {
  // p(th) = x0 + a1 th + a2 th^2 + a3 th^3 + a4 th^4 with p(1) = x1, p'(0) = h f0, p'(1) = h f1,
  // p(1/2) = xm; solved in closed form.
  PolynomialPiece<N> p;
  p.t0 = t0;
  p.t1 = t1;
  p.t_ref = t0;
  p.h = t1 - t0;
  p.degree = 4;
  const Vec<N> d = x1 - x0, g0 = p.h * f0, g1 = p.h * f1, m = xm - x0;
  // Unknowns a2, a3, a4 from: a2 + a3 + a4 = d - g0;  2a2 + 3a3 + 4a4 = g1 - g0;
  // a2/4 + a3/8 + a4/16 = m - g0/2.
  const Vec<N> r1 = d - g0, r2 = g1 - g0, r3 = 16.0 * (m - 0.5 * g0);  // 4a2 + 2a3 + a4 = r3
  // From the first two: a3 = (r2 - 2 r1) - 2 a4; a2 = r1 - a3 - a4 = 3 r1 - r2 + a4.
  // Third: 4(3 r1 - r2 + a4) + 2((r2 - 2 r1) - 2 a4) + a4 = r3  =>  a4 = r3 - 8 r1 + 2 r2.
  const Vec<N> a4 = r3 - 8.0 * r1 + 2.0 * r2;
  const Vec<N> a3 = (r2 - 2.0 * r1) - 2.0 * a4;
  const Vec<N> a2 = 3.0 * r1 - r2 + a4;
  p.c.col(0) = x0;
  p.c.col(1) = g0;
  p.c.col(2) = a2;
  p.c.col(3) = a3;
  p.c.col(4) = a4;
  return p;
}

/// A chain of pieces covering [begin, end] (end < begin for backward integration).
template <int N>
class DenseOutput {
 public:
  using Piece = PolynomialPiece<N>;

  void clear() { pieces_.clear(); }
  void reserve(std::size_t n) { pieces_.reserve(n); }
  void append(const Piece& p) { pieces_.push_back(p); }
  bool empty() const { return pieces_.empty(); }
  std::size_t size() const { return pieces_.size(); }
  const std::vector<Piece>& pieces() const { return pieces_; }

  double begin() const { return pieces_.empty() ? 0.0 : pieces_.front().t0; }
  double end() const { return pieces_.empty() ? 0.0 : pieces_.back().t1; }
  double lo() const { return std::min(begin(), end()); }
  double hi() const { return std::max(begin(), end()); }
  bool covers(double t, double slack = 0.0) const { return !empty() && t >= lo() - slack && t <= hi() + slack; }

  /// The piece containing t (nearest at the ends, so the last step's end point evaluates exactly).
  const Piece& piece(double t) const {
    SALTUS_REQUIRE(!pieces_.empty(), "dense output is empty");
    const bool forward = end() >= begin();
    // Pieces are ordered along the direction of integration.
    std::size_t lo_i = 0, hi_i = pieces_.size();
    while (hi_i - lo_i > 1) {
      const std::size_t mid = (lo_i + hi_i) / 2;
      const bool after = forward ? (t >= pieces_[mid].t0) : (t <= pieces_[mid].t0);
      if (after)
        lo_i = mid;
      else
        hi_i = mid;
    }
    return pieces_[lo_i];
  }
  Vec<N> value(double t) const { return piece(t).value(t); }
  Vec<N> derivative(double t) const { return piece(t).derivative(t); }

 private:
  std::vector<Piece> pieces_;
};

}  // namespace saltus
