// FesdMpcc: construction (the checks of the options and the initial state), the layout of the
// variables and rows, and their names (fesd.hpp).
#pragma once

#include <saltus/hybrid/vocabulary/errors.hpp>
#include <saltus/timefreezing/discretisation/fesd.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace saltus::timefreezing {

/// The FESD NLP's tableau: Radau IIA with n_s in 1 .. 3, the stage counts its cross complementarity
/// and step equilibration are tested with (the refinement takes more, refinement_options.hpp).
inline RadauIIA fesd_radau_tableau(int n_s) {
  SALTUS_REQUIRE(n_s >= 1 && n_s <= 3, "FESD: grid.stages must be 1, 2 or 3, got ", n_s);
  return radau_iia(n_s);
}

template <Scene S, class Ocp>
FesdMpcc<S, Ocp>::FesdMpcc(const System& system, const Ocp& ocp, const Vec<nq>& q0, const Vec<nq>& v0,
                           const FesdOptions& options)
    : system_(system), ocp_(ocp), options_(options), tableau_(fesd_radau_tableau(options.grid.stages)) {
  require_finite(q0, "FESD: initial configuration q0");
  require_finite(v0, "FESD: initial velocity v0");
  check_options();
  y0_.setZero();
  y0_.template head<nq>() = q0;
  y0_.template segment<nq>(nq) = v0;
  y0_[System::clock_index] = options.clock.initial_time;
  for (int i = 0; i < nc; ++i) {
    const double gap = system.scene().template gap<double>(i, q0);
    y0_[System::gap_state_index + i] = gap;
    SALTUS_REQUIRE(gap >= -options.bounds.gap_tolerance, "FESD: the initial state penetrates contact '",
                   system.scene().contact(i).name, "' (gap ", gap, " < -", options.bounds.gap_tolerance, ")");
  }
  n_ = options.grid.control_intervals * interval_size();
  h0_ = options.grid.horizon / (options.grid.control_intervals * options.grid.finite_elements);
  build_rows();
  build_structures();
  build_pairs();
}

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::check_options() const {
  const FesdOptions& o = options_;
  SALTUS_REQUIRE(o.grid.control_intervals >= 1, "FESD: control_intervals must be >= 1, got ", o.grid.control_intervals);
  SALTUS_REQUIRE(o.grid.finite_elements >= 1, "FESD: finite_elements must be >= 1, got ", o.grid.finite_elements);
  SALTUS_REQUIRE(std::isfinite(o.grid.horizon) && o.grid.horizon > 0.0, "FESD: the numerical horizon must be > 0, got ",
                 o.grid.horizon);
  SALTUS_REQUIRE(o.grid.element_length_freedom >= 0.0 && o.grid.element_length_freedom <= 1.0,
                 "FESD: element_length_freedom (gamma_h) must lie in [0, 1], got ", o.grid.element_length_freedom);
  SALTUS_REQUIRE(std::isfinite(o.clock.speed_of_time_max) && o.clock.speed_of_time_max >= 1.0,
                 "FESD: speed_of_time_max must be >= 1, got ", o.clock.speed_of_time_max);
  const auto weight = [](double w) { return std::isfinite(w) && w >= 0.0; };
  SALTUS_REQUIRE(weight(o.regularisation.step_equilibration),
                 "FESD: the step equilibration weight must be >= 0 and finite, got ", o.regularisation.step_equilibration);
  SALTUS_REQUIRE(weight(o.regularisation.speed_of_time), "FESD: the speed-of-time weight must be >= 0 and finite, got ",
                 o.regularisation.speed_of_time);
  SALTUS_REQUIRE(weight(o.regularisation.contact_side), "FESD: the contact-side weight must be >= 0 and finite, got ",
                 o.regularisation.contact_side);
  for (double k : o.switching.scale)
    SALTUS_REQUIRE(std::isfinite(k) && k > 0.0, "FESD: switching_scale entries must be finite and > 0, got ", k);
  SALTUS_REQUIRE(o.clock.constraint == ClockConstraint::None ||
                     (std::isfinite(o.clock.physical_horizon) && o.clock.physical_horizon > 0.0),
                 "FESD: a clock constraint needs physical_horizon > 0, got ", o.clock.physical_horizon);
  SALTUS_REQUIRE(o.bounds.control_lower.size() == 0 || o.bounds.control_lower.size() == nu,
                 "FESD: control_lower must have nu = ", nu, " entries, got ", o.bounds.control_lower.size());
  SALTUS_REQUIRE(o.bounds.control_upper.size() == 0 || o.bounds.control_upper.size() == nu,
                 "FESD: control_upper must have nu = ", nu, " entries, got ", o.bounds.control_upper.size());
  SALTUS_REQUIRE(std::isfinite(o.clock.initial_time), "FESD: initial_time must be finite, got ", o.clock.initial_time);
}

// ---- layout ----------------------------------------------------------------------------------
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::stage_size() const { return 2 * ny + 3 * nsw; }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::stages() const { return options_.grid.stages; }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::element_size() const { return 1 + options_.grid.stages * stage_size(); }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::interval_size() const { return 1 + nu + options_.grid.finite_elements * element_size(); }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::speed_index(int k) const { return k * interval_size(); }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::control_index(int k) const { return speed_index(k) + 1; }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::length_index(int k, int j) const { return control_index(k) + nu + j * element_size(); }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::stage_index(int k, int j, int r) const { return length_index(k, j) + 1 + r * stage_size(); }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::state_index(int k, int j, int r) const { return stage_index(k, j, r); }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::derivative_index(int k, int j, int r) const { return stage_index(k, j, r) + ny; }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::alpha_index(int k, int j, int r) const { return stage_index(k, j, r) + 2 * ny; }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::lambda_p_index(int k, int j, int r) const { return alpha_index(k, j, r) + nsw; }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::lambda_n_index(int k, int j, int r) const { return alpha_index(k, j, r) + 2 * nsw; }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::start_state_index(int k, int j) const {
  if (j > 0) return state_index(k, j - 1, options_.grid.stages - 1);
  if (k > 0) return state_index(k - 1, options_.grid.finite_elements - 1, options_.grid.stages - 1);
  return -1;
}
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::final_state_index() const {
  return state_index(options_.grid.control_intervals - 1, options_.grid.finite_elements - 1, options_.grid.stages - 1);
}
template <Scene S, class Ocp>
double FesdMpcc<S, Ocp>::nominal_element_length() const { return h0_; }
template <Scene S, class Ocp>
auto FesdMpcc<S, Ocp>::system() const -> const System& { return system_; }
template <Scene S, class Ocp>
const FesdOptions& FesdMpcc<S, Ocp>::options() const { return options_; }
template <Scene S, class Ocp>
auto FesdMpcc<S, Ocp>::initial_state() const -> const Eigen::Matrix<double, ny, 1>& { return y0_; }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::variable_count() const { return n_; }
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::constraint_count() const { return m_; }

// ---- rows ------------------------------------------------------------------------------------
// Row blocks in this order: per stage [dynamics ny][collocation ny][switching nsw][path np];
// per control interval, after its stages: [element sum 1][clock 0 or 1]; then [terminal nt].
template <Scene S, class Ocp>
int FesdMpcc<S, Ocp>::stage_row(int k, int j, int r) const {
  return stage_row_[static_cast<std::size_t>((k * options_.grid.finite_elements + j) * options_.grid.stages + r)];
}

template <Scene S, class Ocp>
void FesdMpcc<S, Ocp>::build_rows() {
  const FesdOptions::Grid& grid = options_.grid;
  int row = 0;
  stage_row_.clear();
  interval_row_.clear();
  for (int k = 0; k < grid.control_intervals; ++k) {
    for (int j = 0; j < grid.finite_elements; ++j)
      for (int r = 0; r < grid.stages; ++r) {
        stage_row_.push_back(row);
        row += 2 * ny + nsw + np;
      }
    interval_row_.push_back(row);
    row += 1 + (has_clock_row(k) ? 1 : 0);
  }
  terminal_row_ = row;
  m_ = row + nt;
  // Bounds of the non-equality rows.
  inequality_rows_.clear();
  const FesdOptions::Clock& clock = options_.clock;
  for (int k = 0; k < grid.control_intervals; ++k) {
    const int ir = interval_row_[static_cast<std::size_t>(k)];
    const double dt = grid.horizon / grid.control_intervals;
    inequality_rows_.push_back({ir, dt, dt});
    if (has_clock_row(k)) {
      const double tk = clock.initial_time + (clock.constraint == ClockConstraint::Stagewise
                                                  ? clock.physical_horizon * (k + 1) / grid.control_intervals
                                                  : clock.physical_horizon);
      inequality_rows_.push_back({ir + 1, tk, tk});
    }
    if constexpr (np > 0) {
      const Vec<np> lo = ocp_.path_lower(), hi = ocp_.path_upper();
      for (int j = 0; j < grid.finite_elements; ++j)
        for (int r = 0; r < grid.stages; ++r)
          for (int i = 0; i < np; ++i) inequality_rows_.push_back({stage_row(k, j, r) + 2 * ny + nsw + i, lo[i], hi[i]});
    }
  }
  if constexpr (nt > 0) {
    const Vec<nt> lo = ocp_.terminal_lower(), hi = ocp_.terminal_upper();
    for (int i = 0; i < nt; ++i) inequality_rows_.push_back({terminal_row_ + i, lo[i], hi[i]});
  }
}

template <Scene S, class Ocp>
bool FesdMpcc<S, Ocp>::has_clock_row(int k) const {
  return options_.clock.constraint == ClockConstraint::Stagewise ||
         (options_.clock.constraint == ClockConstraint::Terminal && k == options_.grid.control_intervals - 1);
}
template <Scene S, class Ocp>
double FesdMpcc<S, Ocp>::switching_scale(int m) const {
  return options_.switching.scale[static_cast<std::size_t>(m % 3)];
}
template <Scene S, class Ocp>
bool FesdMpcc<S, Ocp>::reads_integrated_gap(int m) const {
  return options_.switching.integrated_gap && m % 3 == 0;
}
template <Scene S, class Ocp>
bool FesdMpcc<S, Ocp>::switching_active(int m) const {
  return system_.has_friction(m / 3) || m % 3 != 2;
}
// The other active ones get the stage-wise pairs (fesd_complementarity.hxx).
template <Scene S, class Ocp>
bool FesdMpcc<S, Ocp>::cross_complementary(int m) const {
  return switching_active(m) && options_.switching.detection && (options_.switching.velocity_detection || m % 3 == 0);
}

// ---- names -----------------------------------------------------------------------------------
template <Scene S, class Ocp>
std::string FesdMpcc<S, Ocp>::variable_name(int i) const {
  const int k = i / interval_size();
  int rest = i - k * interval_size();
  if (rest == 0) return "s[" + std::to_string(k) + "]";
  if (rest <= nu) return "u[" + std::to_string(k) + "][" + std::to_string(rest - 1) + "]";
  rest -= 1 + nu;
  const int j = rest / element_size();
  rest -= j * element_size();
  const std::string el = "[" + std::to_string(k) + "," + std::to_string(j);
  if (rest == 0) return "h" + el + "]";
  rest -= 1;
  const int r = rest / stage_size();
  rest -= r * stage_size();
  const std::string at = el + "," + std::to_string(r) + "]";
  if (rest < ny) return "Y" + at + "[" + std::to_string(rest) + "]";
  if (rest < 2 * ny) return "K" + at + "[" + std::to_string(rest - ny) + "]";
  rest -= 2 * ny;
  if (rest < nsw) return "alpha" + at + "[" + std::to_string(rest) + "]";
  if (rest < 2 * nsw) return "lambda_p" + at + "[" + std::to_string(rest - nsw) + "]";
  return "lambda_n" + at + "[" + std::to_string(rest - 2 * nsw) + "]";
}

template <Scene S, class Ocp>
std::string FesdMpcc<S, Ocp>::constraint_name(int row) const {
  if (row >= terminal_row_) return "terminal constraint " + std::to_string(row - terminal_row_);
  for (int k = 0; k < options_.grid.control_intervals; ++k) {
    const int ir = interval_row_[static_cast<std::size_t>(k)];
    if (row == ir) return "sum of element lengths [" + std::to_string(k) + "]";
    if (row == ir + 1 && has_clock_row(k)) return "clock [" + std::to_string(k) + "]";
  }
  const auto it = std::upper_bound(stage_row_.begin(), stage_row_.end(), row);
  const int i = static_cast<int>(it - stage_row_.begin()) - 1;
  const int ns = options_.grid.stages, nfe = options_.grid.finite_elements;
  const std::string at = "[" + std::to_string(i / (ns * nfe)) + "," + std::to_string((i / ns) % nfe) + "," +
                         std::to_string(i % ns) + "]";
  const int off = row - stage_row_[static_cast<std::size_t>(i)];
  if (off < ny) return "stage dynamics" + at + "[" + std::to_string(off) + "]";
  if (off < 2 * ny) return "collocation" + at + "[" + std::to_string(off - ny) + "]";
  if (off < 2 * ny + nsw) return "switching function" + at + "[" + std::to_string(off - 2 * ny) + "]";
  return "path constraint" + at + "[" + std::to_string(off - 2 * ny - nsw) + "]";
}

}  // namespace saltus::timefreezing
