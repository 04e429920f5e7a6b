// Where one pass over the FESD rows writes: the constraint values, the Jacobian's values in the
// order of its structure, or that structure itself. One loop fills all three, so the order of the
// entries cannot drift apart between the structure and the values.
#pragma once

#include <saltus/timefreezing/mpcc/mpcc.hpp>

#include <Eigen/Core>

#include <vector>

namespace saltus::timefreezing::detail {

/// A pass over the constraint rows: values into g (when given), Jacobian values into `values`
/// (structure order) or the structure into `structure`.
struct JacobianSink {
  Eigen::Ref<Eigen::VectorXd>* g = nullptr;
  Eigen::Ref<Eigen::VectorXd>* values = nullptr;
  std::vector<SparseEntry>* structure = nullptr;
  int entry = 0;  ///< the running entry index

  /// Whether this pass wants the derivatives (values or structure), not only g.
  bool derivatives() const { return values != nullptr || structure != nullptr; }
  void value(int row, double v) const {
    if (g) (*g)[row] = v;
  }
  void put(int row, int col, double v) {
    if (structure) structure->push_back({row, col});
    if (values) (*values)[entry] = v;
    ++entry;
  }
};

/// A pass over the Lagrangian Hessian's lower triangle: values (structure order) or the structure.
struct HessianSink {
  Eigen::Ref<Eigen::VectorXd>* values = nullptr;
  std::vector<SparseEntry>* structure = nullptr;
  int entry = 0;

  bool evaluating() const { return values != nullptr; }
  /// Entry (a, b) stored in the lower triangle (the larger index is the row).
  void put(int a, int b, double v) {
    if (structure) structure->push_back(a >= b ? SparseEntry{a, b} : SparseEntry{b, a});
    if (values) (*values)[entry] = v;
    ++entry;
  }
};

}  // namespace saltus::timefreezing::detail
