// The Delassus assembly: the constraint rows J, the force columns F and the Delassus matrix
// D = J M^{-1} F of a set of contacts (thesis A.15, A.25, A.33), the one place where a contact's
// rows and columns are stacked. The flow (forces), the jump map (impulses), the mode selection
// (accelerations), the impact problem (velocities) and the constraint projection all start here;
// each then fills its own right-hand side row by row through normal_row / tangent_row.
//
// Per contact, in contact order:
//   ContactRows::Normal  one row w_n^T, column w_n (a frictionless contact, or the normal
//                        direction alone, as in a position-level projection);
//   ContactRows::Slip    one row w_n^T, column w_n - mu W_t d: the friction of a contact slipping
//                        along d (unit, in tangent coordinates) folded into the normal column,
//                        lambda_t = -mu lambda_n d (thesis A.21-A.25); D is then not symmetric;
//   ContactRows::Stick   the normal row, then one row W_t(:,k)^T and column W_t(:,k) per tangent
//                        (a sticking contact, or the full contact of an impact problem; for a
//                        frictionless contact the same as Normal).
// With every contact Normal or Stick, F = J^T and D = J M^{-1} J^T is symmetric positive
// semidefinite, singular when contacts are redundant (a box resting flat on two or four corners).
// M^{-1} is applied with the factorisation of the value of M only (linear_solve.hpp), so T may
// carry derivatives.
#pragma once

#include <saltus/hybrid/contact/linear_solve.hpp>
#include <saltus/hybrid/dynamics/kinematics.hpp>

#include <algorithm>
#include <array>
#include <cstdint>

namespace saltus {

/// How a contact enters a Delassus assembly (file comment).
enum class ContactRows : std::uint8_t { None, Normal, Slip, Stick };

/// J (rows x nq), F (nq x rows), M^{-1} F and D = J M^{-1} F for up to 3 nc rows, stored inline
/// (no allocation after construction). rows = sum over contacts of 1 (Normal, Slip) or
/// 1 + tangents (Stick).
template <Scene S, class T = double>
struct DelassusAssembly {
  static constexpr int nq = S::nq, nc = S::nc;
  static constexpr int max_rows = delassus_bound(std::max(1, 3 * S::nc));
  using RowsMatrix = BoundedMatrix<T, Eigen::Dynamic, nq, max_rows, nq>;
  using ColsMatrix = BoundedMatrix<T, nq, Eigen::Dynamic, nq, max_rows>;
  using SquareMatrix = BoundedMatrix<T, Eigen::Dynamic, Eigen::Dynamic, max_rows, max_rows>;

  RowsMatrix J;
  ColsMatrix F, MinvF;
  SquareMatrix D;
  int rows = 0;
  std::array<int, nc> normal_row{};   ///< row of each contact's normal component (-1: not in it)
  std::array<int, nc> tangent_row{};  ///< first tangential row of each Stick contact (-1: none)

  DelassusAssembly() {
    J.resize(max_rows, nq);
    F.resize(nq, max_rows);
    MinvF.resize(nq, max_rows);
    D.resize(max_rows, max_rows);
  }

  /// Stacks J and F of the contacts by `layout` from their kinematics `kin` (evaluated at the
  /// state of interest). `slip_direction[i]` (unit, tangent coordinates; planar: (+-1, 0)) is read
  /// for Slip contacts with tangents only. Leaves MinvF and D as they were: call form().
  void assemble(const S& scene, const Kinematics<S, T>& kin, const std::array<ContactRows, nc>& layout,
                const std::array<VecT<T, 2>, nc>& slip_direction) {
    int m = 0;
    for (int i = 0; i < nc; ++i) {
      normal_row[i] = -1;
      tangent_row[i] = -1;
      if (layout[i] == ContactRows::None) continue;
      const auto& c = kin.contacts[i];
      const int nt = c.tangents;
      normal_row[i] = m;
      J.row(m) = c.wn.transpose();
      if (layout[i] == ContactRows::Slip && nt > 0) {
        F.col(m) = c.wn - T(scene.contact(i).mu) * (c.Wt.leftCols(nt) * slip_direction[i].head(nt));
        ++m;
        continue;
      }
      F.col(m) = c.wn;
      ++m;
      if (layout[i] != ContactRows::Stick || nt == 0) continue;
      tangent_row[i] = m;
      for (int k = 0; k < nt; ++k, ++m) {
        J.row(m) = c.Wt.col(k).transpose();
        F.col(m) = c.Wt.col(k);
      }
    }
    rows = m;
  }

  /// MinvF = M^{-1} F and D = J M^{-1} F over the assembled rows (nothing when rows = 0).
  void form(const Kinematics<S, T>& kin) {
    if (rows == 0) return;
    kin.solve_mass(F.leftCols(rows), MinvF);
    D.resize(rows, rows);
    D.noalias() = J.topRows(rows) * MinvF;
  }
};

}  // namespace saltus
