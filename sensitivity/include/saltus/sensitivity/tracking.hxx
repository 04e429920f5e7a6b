// Definitions of tracking.hpp (see there for the math).
#pragma once

#include <saltus/hybrid/dynamics/constraints.hpp>
#include <saltus/hybrid/simulation/simulator.hpp>
#include <saltus/sensitivity/detail/dense.hpp>
#include <saltus/sensitivity/detail/ode.hxx>
#include <saltus/sensitivity/linearisation.hxx>
#include <saltus/sensitivity/tracking.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <ostream>
#include <random>
#include <thread>

namespace saltus {

// ---------------------------------------------------------------------------------------------
// GainSchedule

template <Scene S>
GainSchedule<S>::GainSchedule(int segments, const Gain& K) {
  SALTUS_REQUIRE(segments >= 0, "GainSchedule: negative segment count ", segments);
  segments_.resize(segments);
  for (auto& s : segments_) {
    s.times = {0.0};
    s.gains = {K};
  }
}

template <Scene S>
GainSchedule<S>::GainSchedule(std::vector<Gain> per_segment) {
  segments_.resize(per_segment.size());
  for (std::size_t i = 0; i < per_segment.size(); ++i) set_samples(static_cast<int>(i), {0.0}, {per_segment[i]});
}

template <Scene S>
void GainSchedule<S>::set_samples(int i, std::vector<double> times, std::vector<Gain> gains) {
  SALTUS_REQUIRE(i >= 0 && i < segment_count(), "GainSchedule: segment ", i, " out of range [0, ", segment_count(), ")");
  SALTUS_REQUIRE(!times.empty() && times.size() == gains.size(), "GainSchedule: segment ", i, " needs as many gains (",
                 gains.size(), ") as times (", times.size(), "), at least one");
  for (std::size_t k = 0; k < times.size(); ++k) {
    SALTUS_REQUIRE(std::isfinite(times[k]) && (k == 0 || times[k] > times[k - 1]), "GainSchedule: segment ", i,
                   ": sample times must be finite and strictly increasing (sample ", k, ")");
    SALTUS_REQUIRE(gains[k].allFinite(), "GainSchedule: segment ", i, ": gain ", k, " is not finite");
  }
  segments_[i].times = std::move(times);
  segments_[i].gains = std::move(gains);
}

template <Scene S>
auto GainSchedule<S>::operator()(int i, double t) const -> Gain {
  SALTUS_REQUIRE(i >= 0 && i < segment_count(), "GainSchedule: segment ", i, " out of range [0, ", segment_count(), ")");
  const Samples& s = segments_[i];
  if (t <= s.times.front()) return s.gains.front();
  if (t >= s.times.back()) return s.gains.back();
  const auto k = static_cast<std::size_t>(std::upper_bound(s.times.begin(), s.times.end(), t) - s.times.begin());
  const double w = (t - s.times[k - 1]) / (s.times[k] - s.times[k - 1]);
  return (1.0 - w) * s.gains[k - 1] + w * s.gains[k];
}

namespace detail {

// The Cholesky factor's transpose L' of an SPD W = L L' (so |z|_W = |L' z|) and its inverse.
template <int n>
void weight_factor(const Mat<n, n>& W, const char* what, Mat<n, n>& Lt, Mat<n, n>& Lt_inv) {
  SALTUS_REQUIRE(W.allFinite() && (W - W.transpose()).norm() <= 1e-12 * std::max(1.0, W.norm()), what,
                 ": the weight W must be finite and symmetric");
  Eigen::MatrixXd U;
  SALTUS_REQUIRE(cholesky_upper(W, U), what, ": the weight W is not positive definite");
  Lt = U;
  Lt_inv = lu_solve(U, Mat<n, n>::Identity());
}

// |M|_{W -> Wout} = |C M N|_2 (C = Wout^(1/2), or L' for the norm W itself; N = L'^-1, or
// E R^-1 on a subspace: z0 = N y with |y| = |z0|_W).
template <int n, class InputMap>
double weighted_norm(const Mat<n, n>& M, const Mat<n, n>& C, const InputMap& N) {
  if constexpr (n == 0) return 0.0;
  const Eigen::Matrix<double, n, Eigen::Dynamic, 0, n, n> P = C * M * N;
  return largest_singular_value(P);
}

// N with z0 = N y, |y| = |z0|_W, z0 ranging over range(E) (or all of R^n): E R^-1 with L' E = Q R.
template <int n>
Eigen::Matrix<double, n, Eigen::Dynamic, 0, n, n> initial_map(
    const std::optional<Eigen::Matrix<double, n, Eigen::Dynamic, 0, n, n>>& E, const Mat<n, n>& Lt,
    const Mat<n, n>& Lt_inv, const char* what) {
  if (!E) return Lt_inv;
  SALTUS_REQUIRE(E->cols() >= 1 && E->allFinite(), what, ": the initial subspace needs at least one finite column");
  const Eigen::Matrix<double, n, Eigen::Dynamic, 0, n, n> B = Lt * *E;
  const Eigen::MatrixXd R = qr_upper_factor(B);
  const double scale = std::max(1e-300, R.diagonal().cwiseAbs().maxCoeff());
  SALTUS_REQUIRE(R.diagonal().cwiseAbs().minCoeff() > 1e-12 * scale, what,
                 ": the initial subspace's columns are linearly dependent");
  return *E * lu_solve(R, Eigen::MatrixXd::Identity(R.rows(), R.cols()));
}

// C with |z|_Wout = |C z|: the symmetric square root of a PSD Wout, or L' (W = L L') without one.
template <int n>
Mat<n, n> output_factor(const std::optional<Mat<n, n>>& Wout, const Mat<n, n>& Lt, const char* what) {
  if (!Wout) return Lt;
  SALTUS_REQUIRE(Wout->allFinite() && (*Wout - Wout->transpose()).norm() <= 1e-12 * std::max(1.0, Wout->norm()), what,
                 ": the output weight W_out must be finite and symmetric");
  if constexpr (n == 0) return Mat<n, n>();
  Eigen::MatrixXd V;
  const Eigen::VectorXd lambda = symmetric_eigenvalues(*Wout, &V);
  SALTUS_REQUIRE(lambda.minCoeff() >= -1e-12 * std::max(1.0, Wout->norm()), what,
                 ": the output weight W_out must be positive semidefinite (smallest eigenvalue ", lambda.minCoeff(), ")");
  const Eigen::VectorXd root = lambda.cwiseMax(0.0).cwiseSqrt();
  return V * root.asDiagonal() * V.transpose();
}

template <int n>
void require_symmetric_psd(const Mat<n, n>& Q, const char* name) {
  SALTUS_REQUIRE(Q.allFinite() && (Q - Q.transpose()).norm() <= 1e-12 * std::max(1.0, Q.norm()), "lqr_design: ",
                 name, " must be finite and symmetric");
  if constexpr (n > 0) {
    const double lo = symmetric_eigenvalues(Q).minCoeff();
    SALTUS_REQUIRE(lo >= -1e-12 * std::max(1.0, Q.norm()), "lqr_design: ", name,
                   " must be positive semidefinite (smallest eigenvalue ", lo, ")");
  }
}

// Bounds on a growth factor (an amplification or a spectral radius) to a verdict: below 1 for
// sure, above 1 for sure, or between.
inline StabilityVerdict verdict(double lower, double upper) {
  return upper < 1.0 ? StabilityVerdict::Stable : lower > 1.0 ? StabilityVerdict::Unstable : StabilityVerdict::Undecided;
}

// The jump gains (G_z, G_v) through event e of the open loop: the event's own gain, or at a
// simultaneous event every conewise piece with the nominal outcome (the pieces a deviation that
// stays on the reference's event sequence can meet). Shared by lqr_design (the worst piece) and
// ClosedLoopLinearisation::jump_pieces.
template <Scene S>
std::vector<std::pair<Mat<2 * S::nq, 2 * S::nq>, Mat<2 * S::nq, S::nu>>> nominal_jump_gains(
    const LinearisedSystem<S>& open_loop, int e, const char* who) {
  std::vector<std::pair<Mat<2 * S::nq, 2 * S::nq>, Mat<2 * S::nq, S::nu>>> out;
  if (!open_loop.conewise(e)) {
    out.emplace_back(open_loop.gains().at(e).G_z, open_loop.gains().at(e).G_v);
    return out;
  }
  auto& cg = open_loop.conewise_gain(e);
  cg.build_all();
  for (const auto* piece : cg.pieces())
    if (piece->nominal_outcome) out.emplace_back(piece->G_z, piece->G_v);
  SALTUS_CHECK_NUMERICS(!out.empty(), who, ": every piece of the simultaneous event at t = ", open_loop.t_end(e),
                        " has an outcome other than the nominal one");
  return out;
}

// The piece sequences of a run through events with radices[e] pieces each, numbered in mixed
// radix: sequence s chooses piece digits[e] = (s / prod_{f<e} radices[f]) % radices[e] at event e.
inline void piece_sequence(long s, const std::vector<std::size_t>& radices, std::vector<int>& digits) {
  digits.resize(radices.size());
  for (std::size_t e = 0; e < radices.size(); ++e) {
    digits[e] = static_cast<int>(s % static_cast<long>(radices[e]));
    s /= static_cast<long>(radices[e]);
  }
}

template <Scene S>
void require_signal_treatment(const LinearisedSystem<S>& open_loop, const char* who) {
  SALTUS_REQUIRE(open_loop.options().gains.feedback == FeedbackTreatment::Signal, who,
                 ": the LinearisedSystem must linearise the reference with FeedbackTreatment::Signal (the tracking "
                 "controller replaces the reference's own law; its feedback enters through the gain schedule)");
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------
// LQR

template <Scene S>
LqrDesign<S> lqr_design(const LinearisedSystem<S>& ol, const LqrWeights<S>& weights, const LqrOptions& options) {
  constexpr int nx = 2 * S::nq, nu = S::nu;
  using Matrix = Mat<nx, nx>;
  using Gain = Mat<nu, nx>;
  if constexpr (nu == 0) {
    SALTUS_REQUIRE(nu > 0, "lqr_design: the scene has no inputs (nu = 0): there is nothing to design");
    return {};
  } else {
  const auto start = std::chrono::steady_clock::now();
  detail::require_signal_treatment(ol, "lqr_design");
  detail::require_symmetric_psd<nx>(weights.Q, "Q");
  detail::require_symmetric_psd<nx>(weights.Q_final, "Q_final");
  SALTUS_REQUIRE(weights.R.allFinite() && (weights.R - weights.R.transpose()).norm() <= 1e-12 * std::max(1.0, weights.R.norm()),
                 "lqr_design: R must be finite and symmetric");
  // R^-1 once (SPD: Cholesky); the Riccati right-hand side multiplies by it at every stage.
  Eigen::MatrixXd R_inverse_dynamic;
  SALTUS_REQUIRE(detail::spd_solve(weights.R, Mat<nu, nu>::Identity(), R_inverse_dynamic),
                 "lqr_design: R is not positive definite");
  const Mat<nu, nu> R_inverse = R_inverse_dynamic;
  SALTUS_REQUIRE(options.sample_step > 0, "lqr_design: sample_step must be > 0");

  const int n = ol.segment_count();
  LqrDesign<S> design;
  design.gains = GainSchedule<S>(n, Gain::Zero());
  design.P_begin.resize(n);
  design.P_end.resize(n);
  design.worst_piece.assign(std::max(0, n - 1), -1);
  design.jump_iterations.assign(std::max(0, n - 1), 0);

  using Flat = Eigen::Matrix<double, nx * nx, 1>;
  using FlatMap = Eigen::Map<Matrix>;
  using ConstFlatMap = Eigen::Map<const Matrix>;
  Matrix A;
  Mat<nx, nu> B;
  const auto gain_at = [&](int i, double t, const Matrix& P) -> Gain {
    ol.jacobians(i, t, A, B);
    return -R_inverse * (B.transpose() * P);
  };

  Matrix P = weights.Q_final;
  for (int i = n - 1; i >= 0; --i) {
    design.P_end[i] = P;
    const double tb = ol.t_begin(i), te = ol.t_end(i);
    std::vector<double> times;
    std::vector<Matrix> Ps;
    times.push_back(te);
    Ps.push_back(P);
    if (te > tb) {
      // Backwards from te: -P' = A'P + PA - P B R^-1 B' P + Q, sampled every sample_step.
      auto rhs = [&](double t, const Flat& y, Flat& dydt) {
        const ConstFlatMap Pm(y.data());
        ol.jacobians(i, t, A, B);
        Matrix D = A.transpose() * Pm + Pm * A + weights.Q;
        const Mat<nu, nx> BtP = B.transpose() * Pm;
        D.noalias() -= BtP.transpose() * (R_inverse * BtP);
        FlatMap(dydt.data()) = -0.5 * (D + D.transpose());
      };
      detail::Dopri5Settings settings;
      settings.relative_tolerance = options.riccati.relative;
      settings.absolute_tolerance = options.riccati.absolute;
      settings.initial_step = options.riccati.initial_step;
      settings.max_steps = options.riccati.max_steps;
      settings.what = "backward Riccati integration";
      detail::Dopri5Stepper<Flat> stepper;
      detail::Dopri5Steps steps;
      Flat y;
      FlatMap(y.data()) = P;
      double t = te;
      double next = te - options.sample_step;
      detail::dopri5_integrate(stepper, rhs, t, y, tb, settings, steps,
                               [&](double ta, const Flat& ya, const Flat& fa, double tb_, const Flat& yb, const Flat& fb) {
                                 Flat ys;
                                 while (next > tb_ && next > tb) {
                                   stepper.calc_state(next, ys, ya, fa, ta, yb, fb, tb_);
                                   times.push_back(next);
                                   Ps.push_back(ConstFlatMap(ys.data()));
                                   next -= options.sample_step;
                                 }
                                 return false;
                               });
      P = ConstFlatMap(y.data());
      P = (0.5 * (P + P.transpose())).eval();
      times.push_back(tb);
      Ps.push_back(P);
    }
    design.P_begin[i] = P;
    // The schedule in increasing time.
    std::reverse(times.begin(), times.end());
    std::reverse(Ps.begin(), Ps.end());
    std::vector<Gain> Ks(times.size());
    for (std::size_t k = 0; k < times.size(); ++k) Ks[k] = gain_at(i, times[k], Ps[k]);
    if (times.size() > 1 && times[1] <= times[0]) {  // te == tb: a single sample
      times.resize(1);
      Ks.resize(1);
    }
    design.gains.set_samples(i, times, Ks);
    if (i == 0) break;

    // The cost-to-go jump through event i - 1 (at t* = tb, from segment i - 1 to i).
    const int e = i - 1;
    const double ts = ol.t_end(e);
    const auto candidates = detail::nominal_jump_gains(ol, e, "lqr_design");  // (G_z, G_v) per nominal piece
    const Matrix P_plus = P;
    double worst = -std::numeric_limits<double>::infinity();
    Matrix P_minus = Matrix::Zero();
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      const auto& [Gz, Gv] = candidates[c];
      // P- = J' P+ J with J = G_z + G_v K(P-): fixed point from K = 0 (exact in one step when G_v = 0).
      Matrix Pm = Gz.transpose() * P_plus * Gz;
      int it = 1;
      if (Gv.norm() > 0) {
        for (;; ++it) {
          const Gain K = gain_at(e, ts, Pm);
          const Matrix J = Gz + Gv * K;
          const Matrix next = J.transpose() * P_plus * J;
          const double change = (next - Pm).norm() / std::max(1e-300, next.norm());
          Pm = 0.5 * (next + next.transpose());
          if (change <= options.jump_tolerance) break;
          SALTUS_CHECK_NUMERICS(it < options.jump_iterations, "lqr_design: the cost-to-go jump at the event at t = ",
                                ts, " does not converge in ", options.jump_iterations,
                                " fixed-point iterations (relative change ", change, ")");
        }
      }
      const double lmax = nx > 0 ? detail::symmetric_eigenvalues(Pm).maxCoeff() : 0.0;
      if (lmax > worst) {
        worst = lmax;
        P_minus = Pm;
        design.jump_iterations[e] = it;
        design.worst_piece[e] = ol.conewise(e) ? static_cast<int>(c) : -1;
      }
    }
    P = P_minus;
  }
  design.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return design;
  }
}

// ---------------------------------------------------------------------------------------------
// The controller

template <Scene S>
ReferenceSpreadingController<S>::ReferenceSpreadingController(const ExtendedReference<S>& reference,
                                                              GainSchedule<S> gains)
    : reference_(reference), gains_(std::move(gains)) {
  SALTUS_REQUIRE(gains_.segment_count() == reference_.segment_count(), "ReferenceSpreadingController: the gain ",
                 "schedule has ", gains_.segment_count(), " segments, the reference ", reference_.segment_count());
  for (const auto& ev : reference_.reference().events)
    simultaneous_.push_back(!ev.transitions.empty() && ev.transitions.front().guards.size() > 1);
}

template <Scene S>
auto ReferenceSpreadingController<S>::input(int i, double t, const State& x) const -> Input {
  SALTUS_REQUIRE(i >= 0 && i < reference_.segment_count(), "ReferenceSpreadingController: segment ", i,
                 " out of range [0, ", reference_.segment_count(), ")");
  // Beyond the extended interval the reference is held at the extension's end (tracking.hpp).
  const double tc = std::clamp(t, reference_.reached_before(i), reference_.reached_after(i));
  Input u = reference_.input(i, tc);
  if constexpr (nu > 0) u.noalias() += gains_(i, t) * (x - reference_.state(i, tc));
  return u;
}

namespace detail {

/// "contact 0 stick, contact 1 open" (a slip with the sign of its first tangent direction).
template <int NC>
std::string describe_contact_modes(const Mode<NC>& mode) {
  std::string out;
  for (int i = 0; i < NC; ++i) {
    out += (i > 0 ? ", contact " : "contact ") + std::to_string(i) + " " + to_string(mode[i].mode);
    if (mode[i].mode == ContactMode::Slip) out += mode[i].slip_direction[0] >= 0.0 ? "+" : "-";
  }
  return out;
}

}  // namespace detail

template <Scene S>
auto ReferenceSpreadingController<S>::next_phase(const Phase& before, const Mode<nc>& mode_before,
                                                 const Mode<nc>& mode) const -> Phase {
  const int j = before.segment;
  if (j + 1 >= reference_.segment_count())
    throw UnplannedEvent(detail::concat("reference spreading: the plant has an event after reference segment ", j,
                                        ", the reference's last (it has ", reference_.segment_count() - 1,
                                        " events): no segment to compare with (the plant's mode after it: ",
                                        detail::describe_contact_modes(mode), "; the segment's: ",
                                        detail::describe_contact_modes(reference_.reference().segments[j].mode), ")"));
  const Mode<nc>& here = reference_.reference().segments[j].mode;
  const Mode<nc>& next = reference_.reference().segments[j + 1].mode;
  if (before.intermediate || simultaneous_[j]) {
    if (mode == next) return Phase{j + 1, false};
    return Phase{j, true};
  }
  if (mode == next) return Phase{j + 1, false};
  // A micro-event ahead of a reference event that opens or closes a contact (file comment).
  const auto same_closed_contacts = [](const Mode<nc>& a, const Mode<nc>& b) {
    for (int c = 0; c < nc; ++c)
      if (a[c].closed() != b[c].closed()) return false;
    return true;
  };
  if (same_closed_contacts(mode_before, here) && same_closed_contacts(mode, here) && !same_closed_contacts(next, here))
    return Phase{j, false, true};
  return Phase{j + 1, false};
}

template <Scene S>
SegmentedInputLaw<S> ReferenceSpreadingController<S>::law() const {
  // The plant's history: the phase of every plant segment finished so far, and the last mode seen
  // with each index (the simulator calls the law with segment k's actual mode while it
  // integrates k; while it resolves the event after k it calls with k + 1 and candidate modes).
  struct History {
    std::vector<Phase> phase{Phase{}};
    std::vector<Mode<nc>> mode;
  };
  auto history = std::make_shared<History>();
  return [this, history](int k, double t, const State& x, const Mode<nc>& mode) -> Input {
    History& h = *history;
    SALTUS_REQUIRE(k >= 0, "ReferenceSpreadingController: negative plant segment ", k);
    if (static_cast<int>(h.mode.size()) <= k) h.mode.resize(k + 1, mode);
    // Phases of the plant segments before k are final: their modes were the ones integrated.
    while (static_cast<int>(h.phase.size()) < k) {
      const std::size_t j = h.phase.size();
      h.phase.push_back(next_phase(h.phase[j - 1], h.mode[j - 1], h.mode[j]));
    }
    const Phase p = k == 0 ? h.phase[0]
                    : k < static_cast<int>(h.phase.size()) ? h.phase[k]
                                                           : next_phase(h.phase[k - 1], h.mode[k - 1], mode);
    h.mode[k] = mode;
    if (p.intermediate || p.micro_event_ahead)  // ante-event feedforward (file comment)
      return reference_.input(p.segment, std::clamp(t, reference_.reached_before(p.segment),
                                                     reference_.reached_after(p.segment)));
    return input(p.segment, t, x);
  };
}

// ---------------------------------------------------------------------------------------------
// Closed-loop linearisation

template <Scene S>
ClosedLoopLinearisation<S>::ClosedLoopLinearisation(const LinearisedSystem<S>& open_loop, GainSchedule<S> gains,
                                                    std::optional<detail::OdeTolerances> tolerances)
    : open_loop_(open_loop),
      gains_(std::move(gains)),
      tolerances_(tolerances ? *tolerances : open_loop.options().variational) {
  detail::require_signal_treatment(open_loop, "ClosedLoopLinearisation");
  SALTUS_REQUIRE(gains_.segment_count() == open_loop.segment_count(), "ClosedLoopLinearisation: the gain schedule ",
                 "has ", gains_.segment_count(), " segments, the reference ", open_loop.segment_count());
  SALTUS_REQUIRE(tolerances_.relative > 0 && tolerances_.absolute > 0, "ClosedLoopLinearisation: tolerances must be > 0");
  segment_transition_.resize(segment_count());
}

template <Scene S>
auto ClosedLoopLinearisation<S>::segment_transition(int i) const -> const Matrix& {
  auto& cached = segment_transition_.at(i);
  if (!cached) cached = flow_transition(i, open_loop_.t_end(i), open_loop_.t_begin(i));
  return *cached;
}

template <Scene S>
std::vector<double> ReferenceSpreadingController<S>::breakpoints() const {
  std::vector<double> out;
  for (int i = 0; i < gains_.segment_count(); ++i)
    if (gains_.times(i).size() > 1) out.insert(out.end(), gains_.times(i).begin(), gains_.times(i).end());
  const std::vector<double>& jumps = reference_.reference().input_breakpoints;  // u_i(t) jumps there
  out.insert(out.end(), jumps.begin(), jumps.end());
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

template <Scene S>
auto ClosedLoopLinearisation<S>::closed_loop_matrix(int i, double t) const -> Matrix {
  Matrix A;
  Mat<nx, nu> B;
  open_loop_.jacobians(i, t, A, B);
  if constexpr (nu > 0) A.noalias() += B * gains_(i, t);
  return A;
}

template <Scene S>
auto ClosedLoopLinearisation<S>::flow_transition(int i, double t1, double t0) const -> Matrix {
  using Flat = Eigen::Matrix<double, nx * nx, 1>;
  Flat y;
  Eigen::Map<Matrix>(y.data()).setIdentity();
  if (t1 == t0) return Matrix::Identity();
  auto rhs = [&](double t, const Flat& a, Flat& dadt) {
    Eigen::Map<Matrix>(dadt.data()).noalias() = closed_loop_matrix(i, t) * Eigen::Map<const Matrix>(a.data());
  };
  // The schedule's sample times are kinks of K (linear interpolation): the integration stops at
  // each, so no step straddles one (a kink inside a step makes the error control cut the step
  // to round-off size; measured on the plank-box's LQR: 7.5 s for the check, see tracking.hpp).
  // Each piece starts with its own length as the first step (it is smooth inside).
  const std::vector<double>& kinks = gains_.times(i);
  const double direction = t1 > t0 ? 1.0 : -1.0;
  detail::OdeTolerances tol = tolerances_;
  double t = t0;
  auto k = direction > 0 ? std::upper_bound(kinks.begin(), kinks.end(), t0) : std::lower_bound(kinks.begin(), kinks.end(), t0);
  while (t != t1) {
    double next = t1;
    if (direction > 0) {
      if (k != kinks.end() && *k < t1) next = *k++;
    } else if (k != kinks.begin() && *(k - 1) > t1) {
      next = *--k;
    }
    tol.initial_step = std::abs(next - t);
    detail::integrate_adaptive(rhs, y, t, next, tol);
    t = next;
  }
  return Eigen::Map<const Matrix>(y.data());
}

template <Scene S>
auto ClosedLoopLinearisation<S>::jump(int i) const -> Matrix {
  if (open_loop_.conewise(i))
    throw SimultaneousActivation(detail::concat("ClosedLoopLinearisation::jump: the event at t = ", open_loop_.t_end(i),
                                                " is simultaneous: its closed-loop jump is conewise (jump_pieces)"));
  const JumpGain<S>& g = open_loop_.gains().at(i);
  Matrix J = g.G_z;
  if constexpr (nu > 0) J.noalias() += g.G_v * gains_(i, open_loop_.t_end(i));
  return J;
}

template <Scene S>
auto ClosedLoopLinearisation<S>::jump_pieces(int i) const -> std::vector<Matrix> {
  if (!open_loop_.conewise(i)) return {jump(i)};
  std::vector<Matrix> out;
  const Mat<nu, nx> K = gains_(i, open_loop_.t_end(i));  // the ante-event gain, the same for every piece
  for (const auto& [Gz, Gv] : detail::nominal_jump_gains(open_loop_, i, "ClosedLoopLinearisation::jump_pieces")) {
    Matrix J = Gz;
    if constexpr (nu > 0) J.noalias() += Gv * K;
    out.push_back(J);
  }
  return out;
}

template <Scene S>
int ClosedLoopLinearisation<S>::off_nominal_pieces(int i) const {
  if (!open_loop_.conewise(i)) return 0;
  auto& cg = open_loop_.conewise_gain(i);
  cg.build_all();
  int k = 0;
  for (const auto* piece : cg.pieces()) k += piece->nominal_outcome ? 0 : 1;
  return k;
}

template <Scene S>
auto ClosedLoopLinearisation<S>::apply_jump(int i, const State& z) const -> State {
  if (!open_loop_.conewise(i)) return jump(i) * z;
  Mat<nu, nx> K = gains_(i, open_loop_.t_end(i));
  Vec<nu> v = Vec<nu>::Zero();
  if constexpr (nu > 0) v = K * z;
  const ConewisePiece<S>& piece = open_loop_.conewise_gain(i).piece(z, v);
  if (!piece.nominal_outcome)
    throw SimultaneousActivation(detail::concat("ClosedLoopLinearisation: at the simultaneous event at t = ",
                                                open_loop_.t_end(i), " the deviation lies in the cone of an order whose ",
                                                "outcome is not the nominal one: no segment to continue on"));
  State out = piece.G_z * z;
  if constexpr (nu > 0) out.noalias() += piece.G_v * v;
  return out;
}

template <Scene S>
auto ClosedLoopLinearisation<S>::propagate(const State& z0, double t) const -> State {
  const auto& traj = open_loop_.reference().reference();
  const int last = traj.segment_at(t);
  State z = z0;
  for (int i = 0; i < last; ++i) z = apply_jump(i, segment_transition(i) * z);
  // At the last segment's end (monte_carlo's default t_final) the cached transition is the same
  // integration. Integrating it again for every run took 123 s of a 128 s batch of 100 runs on the
  // optimised plank-box landing (examples/plank_box --json: 1.5 s of LQR gains, a kink every 1 ms
  // to step across); with the cache the batch takes 7.0 s, with the same figures to every digit.
  if (t == open_loop_.t_end(last)) return segment_transition(last) * z;
  return flow_transition(last, t, open_loop_.t_begin(last)) * z;
}

// ---------------------------------------------------------------------------------------------
// Stability along a finite reference

template <Scene S>
StabilityReport check_stability(const ClosedLoopLinearisation<S>& cl, const StabilityOptions<S>& options,
                                double t_final) {
  constexpr int nx = 2 * S::nq;
  using Matrix = Mat<nx, nx>;
  using State = Vec<nx>;
  const auto start = std::chrono::steady_clock::now();
  const LinearisedSystem<S>& ol = cl.open_loop();
  const auto& traj = ol.reference().reference();
  Matrix Lt, Lt_inv;
  detail::weight_factor<nx>(options.weight, "check_stability", Lt, Lt_inv);
  const Matrix C = detail::output_factor<nx>(options.output_weight, Lt, "check_stability");
  const auto N = detail::initial_map<nx>(options.initial_subspace, Lt, Lt_inv, "check_stability");
  SALTUS_REQUIRE(options.samples_per_segment >= 1, "check_stability: samples_per_segment must be >= 1");
  const double t0 = ol.t_begin(0);
  const double T = t_final < 0 ? ol.t_end(ol.segment_count() - 1) : t_final;
  SALTUS_REQUIRE(T > t0 && T <= ol.t_end(ol.segment_count() - 1) * (1 + 1e-15) + 1e-300,
                 "check_stability: t_final = ", T, " is outside the reference (", t0, ", ",
                 ol.t_end(ol.segment_count() - 1), "]");
  const int L = traj.segment_at(T);
  const auto norm = [&](const Matrix& M) { return detail::weighted_norm<nx>(M, C, N); };
  const auto wnorm = [&](const State& z) { return (Lt * z).norm(); };  // of the initial deviation
  const auto onorm = [&](const State& z) { return (C * z).norm(); };   // of the deviation at t

  // Per segment: sample times in (t_begin, t_end] (to T on the last) and Phi_i(t_k, t_begin).
  std::vector<std::vector<Matrix>> samples(L + 1);
  std::vector<std::vector<double>> sample_times(L + 1);
  for (int i = 0; i <= L; ++i) {
    const double tb = ol.t_begin(i), te = i == L ? T : ol.t_end(i);
    Matrix Phi = Matrix::Identity();
    double t = tb;
    for (int k = 1; k <= options.samples_per_segment; ++k) {
      const double tk = k == options.samples_per_segment ? te : tb + (te - tb) * k / options.samples_per_segment;
      if (tk > t) Phi = (cl.flow_transition(i, tk, t) * Phi).eval();
      t = tk;
      samples[i].push_back(Phi);
      sample_times[i].push_back(tk);
    }
  }
  // The jumps: every nominal piece's closed-loop matrix.
  std::vector<std::vector<Matrix>> jumps(L);
  StabilityReport r;
  r.t0 = t0;
  r.t_final = T;
  long sequences = 1;
  for (int e = 0; e < L; ++e) {
    jumps[e] = cl.jump_pieces(e);
    r.off_nominal_pieces += cl.off_nominal_pieces(e);
    SALTUS_CHECK_NUMERICS(!jumps[e].empty(), "check_stability: the simultaneous event at t = ", ol.t_end(e),
                          " has no piece with the nominal outcome");
    if (sequences <= options.max_sequences) sequences *= static_cast<long>(jumps[e].size());
  }
  r.tail_amplification = norm(samples[L].back());
  const double t_last = ol.t_begin(L);
  r.tail_rate = T > t_last ? std::log(r.tail_amplification) / (T - t_last) : 0.0;

  // Upper bounds: exhaustive over piece sequences, else sub-multiplicative.
  std::vector<Matrix> finals;  // Phi_s(T, t0) per enumerated sequence
  if (sequences <= options.max_sequences) {
    r.sequences = sequences;
    std::vector<std::size_t> radices(L);
    for (int e = 0; e < L; ++e) radices[e] = jumps[e].size();
    std::vector<int> choice;
    for (long s = 0; s < sequences; ++s) {
      detail::piece_sequence(s, radices, choice);
      Matrix Psi = Matrix::Identity();
      for (int i = 0; i <= L; ++i) {
        for (std::size_t k = 0; k < samples[i].size(); ++k) {
          const double a = norm(samples[i][k] * Psi);
          if (a > r.peak_upper) {
            r.peak_upper = a;
            r.peak_time = sample_times[i][k];
          }
        }
        Psi = (samples[i].back() * Psi).eval();
        if (i < L) Psi = (jumps[i][choice[i]] * Psi).eval();
      }
      finals.push_back(Psi);
      r.upper_bound = std::max(r.upper_bound, norm(Psi));
    }
  } else {
    r.exhaustive = false;
    r.sequences = 0;
    double running = 1.0;
    for (int i = 0; i <= L; ++i) {
      for (std::size_t k = 0; k < samples[i].size(); ++k) {
        const double a = running * norm(samples[i][k]);
        if (a > r.peak_upper) {
          r.peak_upper = a;
          r.peak_time = sample_times[i][k];
        }
      }
      running *= norm(samples[i].back());
      if (i < L) {
        double worst = 0.0;
        for (const Matrix& J : jumps[i]) worst = std::max(worst, norm(J));
        running *= worst;
      }
    }
    r.upper_bound = running;
  }

  // Lower bounds: what the conewise map itself does to candidate deviations.
  std::vector<State> candidates;
  for (const Matrix& F : finals) {
    using Wide = Eigen::Matrix<double, nx, Eigen::Dynamic, 0, nx, nx>;
    const Wide P = C * F * N;
    const State v = N * detail::top_right_singular_vector(P);
    candidates.push_back(v);
    candidates.push_back(-v);
  }
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal;
  for (int k = 0; k < options.random_directions; ++k) {
    Eigen::VectorXd y(N.cols());
    for (auto& c : y) c = normal(rng);
    candidates.push_back(N * y);
  }
  for (const State& z0 : candidates) {
    const double n0 = wnorm(z0);
    if (!(n0 > 0)) continue;
    State z = z0;
    try {
      for (int i = 0; i <= L; ++i) {
        for (const Matrix& M : samples[i]) r.peak_lower = std::max(r.peak_lower, onorm(M * z) / n0);
        z = samples[i].back() * z;
        if (i < L) z = cl.apply_jump(i, z);
      }
    } catch (const SimultaneousActivation&) {
      continue;  // an off-nominal order: no reference-spreading error to measure
    }
    r.lower_bound = std::max(r.lower_bound, onorm(z) / n0);
  }
  if (r.exhaustive) r.lower_bound = std::min(r.lower_bound, r.upper_bound);  // round-off of the same matrix
  r.upper_rate = std::log(r.upper_bound) / (T - t0);
  r.lower_rate = std::log(r.lower_bound) / (T - t0);
  r.verdict = detail::verdict(r.lower_bound, r.upper_bound);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

// ---------------------------------------------------------------------------------------------
// Periodic references

template <Scene S>
PeriodicStabilityReport check_periodic_stability(const ClosedLoopLinearisation<S>& cl, double period,
                                                 const StabilityOptions<S>& options, double tolerance) {
  constexpr int nx = 2 * S::nq;
  using Matrix = Mat<nx, nx>;
  using State = Vec<nx>;
  const auto start = std::chrono::steady_clock::now();
  const LinearisedSystem<S>& ol = cl.open_loop();
  const auto& traj = ol.reference().reference();
  Matrix Lt, Lt_inv;
  detail::weight_factor<nx>(options.weight, "check_periodic_stability", Lt, Lt_inv);
  const double t0 = ol.t_begin(0), T = t0 + period;
  const double t_end = ol.t_end(ol.segment_count() - 1);
  SALTUS_REQUIRE(period > 0 && T <= t_end * (1 + 1e-15) + 1e-300, "check_periodic_stability: the period ", period,
                 " must be > 0 and end inside the reference (which ends at ", t_end, ")");
  const int L = traj.segment_at(T);
  const State x0 = traj.state(0, t0), xT = traj.state(L, T);
  SALTUS_REQUIRE((xT - x0).norm() <= tolerance * std::max(1.0, x0.norm()) &&
                     traj.segments[L].mode == traj.segments[0].mode,
                 "check_periodic_stability: the reference does not repeat after ", period, " s: |x(t0 + P) - x(t0)| = ",
                 (xT - x0).norm(), " (tolerance ", tolerance, ", relative), modes ", describe(ol.scene(), traj.segments[0].mode),
                 " and ", describe(ol.scene(), traj.segments[L].mode));
  const auto norm = [&](const Matrix& M) { return detail::weighted_norm<nx>(M, Lt, Lt_inv); };

  std::vector<Matrix> flows(L + 1);
  for (int i = 0; i <= L; ++i) flows[i] = i < L ? cl.segment_transition(i) : cl.flow_transition(L, T, ol.t_begin(L));
  std::vector<std::vector<Matrix>> jumps(L);
  long sequences = 1;
  for (int e = 0; e < L; ++e) {
    jumps[e] = cl.jump_pieces(e);
    SALTUS_CHECK_NUMERICS(!jumps[e].empty(), "check_periodic_stability: the simultaneous event at t = ", ol.t_end(e),
                          " has no piece with the nominal outcome");
    sequences *= static_cast<long>(jumps[e].size());
    SALTUS_REQUIRE(sequences <= options.max_sequences, "check_periodic_stability: more than ", options.max_sequences,
                   " piece sequences in one period");
  }
  PeriodicStabilityReport r;
  r.period = period;
  r.sequences = sequences;
  std::vector<Matrix> M(sequences);
  std::vector<std::size_t> radices(L);
  for (int e = 0; e < L; ++e) radices[e] = jumps[e].size();
  std::vector<int> choice;
  for (long s = 0; s < sequences; ++s) {
    detail::piece_sequence(s, radices, choice);
    Matrix Psi = Matrix::Identity();
    for (int i = 0; i <= L; ++i) {
      Psi = (flows[i] * Psi).eval();
      if (i < L) Psi = (jumps[i][choice[i]] * Psi).eval();
    }
    M[s] = Psi;
  }
  const auto rho = [](const Matrix& A) {
    if constexpr (nx == 0) return 0.0;
    return detail::eigenvalues(A).cwiseAbs().maxCoeff();
  };
  if (sequences == 1) {
    Eigen::VectorXd moduli = detail::eigenvalues(M[0]).cwiseAbs();
    std::sort(moduli.data(), moduli.data() + moduli.size(), std::greater<double>());
    r.eigenvalue_moduli.assign(moduli.data(), moduli.data() + moduli.size());
    r.spectral_radius_upper = r.spectral_radius_lower = moduli.size() ? moduli(0) : 0.0;
    r.jsr_depth = 0;
  } else {
    // Upper: min over k of max over products of length k of |p|_W^(1/k) (Jungers 2009, Prop. 1.6).
    r.spectral_radius_upper = std::numeric_limits<double>::infinity();
    for (int k = 1; k <= options.jsr_depth; ++k) {
      long count = 1;
      for (int j = 0; j < k && count <= options.max_sequences; ++j) count *= sequences;
      if (count > options.max_sequences) break;
      double worst = 0.0;
      const std::vector<std::size_t> words(k, static_cast<std::size_t>(sequences));  // products of k period maps
      std::vector<int> word;
      for (long p = 0; p < count; ++p) {
        detail::piece_sequence(p, words, word);
        Matrix prod = Matrix::Identity();
        for (int j = 0; j < k; ++j) prod = (M[word[j]] * prod).eval();
        worst = std::max(worst, std::pow(norm(prod), 1.0 / k));
      }
      if (worst < r.spectral_radius_upper) {
        r.spectral_radius_upper = worst;
        r.jsr_depth = k;
      }
    }
    // Lower: sequences that repeat themselves along their own dominant eigenvector.
    for (long s = 0; s < sequences; ++s) {
      Eigen::MatrixXcd vectors;
      const Eigen::VectorXcd values = detail::eigenvalues(M[s], &vectors);
      int top = 0;
      values.cwiseAbs().maxCoeff(&top);
      const auto lambda = values(top);
      if (std::abs(lambda.imag()) > 1e-12 * std::abs(lambda) || lambda.real() <= 0) continue;
      State z0 = vectors.col(top).real();
      z0 /= z0.norm();
      State z = z0;
      try {
        for (int i = 0; i <= L; ++i) {
          z = flows[i] * z;
          if (i < L) z = cl.apply_jump(i, z);
        }
      } catch (const SimultaneousActivation&) {
        continue;
      }
      if ((z - lambda.real() * z0).norm() <= 1e-8 * std::max(1.0, std::abs(lambda.real())))
        r.spectral_radius_lower = std::max(r.spectral_radius_lower, rho(M[s]));
    }
  }
  r.verdict = detail::verdict(r.spectral_radius_lower, r.spectral_radius_upper);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

// ---------------------------------------------------------------------------------------------
// Monte Carlo

namespace detail {

/// |z(t_k)|_Wout / |d|_W of the first-order closed loop from z(t0) = d at monte_carlo's
/// deviation_times: z carried across the segments before segments[k] by their transitions and
/// the events' closed-loop jumps, then by flows[k] = Phi(t_k, start of segments[k]). NaN from
/// the first sample after a conewise jump whose cone has no nominal piece.
template <Scene S>
std::vector<double> predicted_deviations(const ClosedLoopLinearisation<S>& cl, const std::vector<int>& segments,
                                         const std::vector<Mat<2 * S::nq, 2 * S::nq>>& flows,
                                         const Vec<2 * S::nq>& d, const Mat<2 * S::nq, 2 * S::nq>& C,
                                         double d_norm) {
  std::vector<double> out(segments.size(), std::numeric_limits<double>::quiet_NaN());
  Vec<2 * S::nq> z = d;
  int i = 0;
  try {
    for (std::size_t k = 0; k < segments.size(); ++k) {
      for (; i < segments[k]; ++i) z = cl.apply_jump(i, cl.segment_transition(i) * z);
      out[k] = (C * (flows[k] * z)).norm() / d_norm;
    }
  } catch (const SimultaneousActivation&) {
  }
  return out;
}

/// x(t_k) - x_j(t_k) of one plant run at `times`: the plant on its segment at t_k (after an event
/// at the event's time) against the reference segment of that plant segment's phase
/// (phase_segments, the controller's bookkeeping), extended by reference spreading; NaN where t_k
/// lies beyond that segment's extension.
template <Scene S>
std::vector<Vec<2 * S::nq>> errors_at(const HybridTrajectory<S>& plant, const std::vector<int>& phase_segments,
                                      const ExtendedReference<S>& reference, const std::vector<double>& times) {
  std::vector<Vec<2 * S::nq>> out(times.size(), Vec<2 * S::nq>::Constant(std::numeric_limits<double>::quiet_NaN()));
  for (std::size_t k = 0; k < times.size(); ++k) {
    const double t = times[k];
    const int j = plant.segment_at(t);
    const int s = phase_segments[static_cast<std::size_t>(j)];
    if (t < reference.reached_before(s) || t > reference.reached_after(s)) continue;
    const double tj = std::min(t, plant.segments[static_cast<std::size_t>(j)].t_end);
    out[k] = plant.state(j, tj) - reference.state(s, t);
  }
  return out;
}

/// The errors of one closed-loop run against the reference at T and at the deviation times
/// (errors_at).
template <Scene S>
struct RunErrors {
  Vec<2 * S::nq> at_end;
  std::vector<Vec<2 * S::nq>> at_times;
};

/// Where the plant's event into segment k leaves the reference's event sequence, given the phase
/// after it (file comment, ReferenceSpreadingController::next_phase): a mode other than the phase
/// segment's, or a bounce (a touchdown that leaves the contacts as they were: a micro-event for the
/// controller, but a touchdown and a lift-off the reference does not have). Empty: it keeps it.
template <Scene S>
std::string departure_at_event(const HybridTrajectory<S>& plant, int k, const HybridTrajectory<S>& ref,
                               const typename ReferenceSpreadingController<S>::Phase& phase) {
  const Event<S>& event = plant.events[static_cast<std::size_t>(k - 1)];
  const auto& mode = plant.segments[static_cast<std::size_t>(k)].mode;
  if (!phase.intermediate && !phase.micro_event_ahead && !(mode == ref.segments[phase.segment].mode))
    return concat("the plant's event into ", describe_contact_modes(mode), " where reference segment ", phase.segment,
                  " has ", describe_contact_modes(ref.segments[phase.segment].mode), " (t = ", event.t, " s)");
  const auto& guards = event.guards();
  if (phase.micro_event_ahead &&
      std::any_of(guards.begin(), guards.end(), [](const Guard& g) { return g.kind == GuardKind::Touchdown; }))
    return concat("a bounce: the plant's touchdown into ", describe_contact_modes(mode),
                  " ahead of the event that ends reference segment ", phase.segment, " (t = ", event.t, " s)");
  return {};
}

/// Simulates the closed loop of `controller` from `start` on [t0, T] with `simulator` and follows
/// it through the controller's phases: `o` gets whether it failed and why, whether it kept the
/// event sequence or where it left it, and its event count (observed and predicted untouched);
/// `last` is the reference segment at T. What the simulation throws is o's failure, not rethrown.
template <Scene S>
RunErrors<S> track_run(Simulator<S>& simulator, const ReferenceSpreadingController<S>& controller,
                       const Vec<2 * S::nq>& start, double t0, double T, int last, const std::vector<double>& times,
                       MonteCarloRun& o) {
  using Phase = typename ReferenceSpreadingController<S>::Phase;
  RunErrors<S> out;
  try {
    const HybridTrajectory<S> traj = simulator.run(start, t0, T, controller.law());
    if (traj.status != SimulationStatus::Completed) {
      o.failed = true;
      o.reason = concat("simulation ended with status ", to_string(traj.status));
      return out;
    }
    o.events = static_cast<int>(traj.events.size());
    const ExtendedReference<S>& extended = controller.reference();
    Phase phase;  // the plant's phase after each of its events (the controller's own bookkeeping)
    std::vector<int> phase_segments(static_cast<std::size_t>(traj.segment_count()), 0);
    for (int k = 1; k < traj.segment_count(); ++k) {
      const Phase before = phase;
      phase = controller.next_phase(phase, traj.segments[k - 1].mode, traj.segments[k].mode);
      phase_segments[static_cast<std::size_t>(k)] = phase.segment;
      if (o.departure.empty()) o.departure = departure_at_event(traj, k, extended.reference(), phase);
      // The controller held the reference beyond an extension (tracking.hpp): not a valid run.
      const double te = traj.events[k - 1].t;
      if (te > extended.reached_after(before.segment) || te < extended.reached_before(phase.segment)) {
        o.failed = true;
        o.reason = concat("the plant's event at t = ", te, " lies beyond the extension of reference segment ",
                          te > extended.reached_after(before.segment) ? before.segment : phase.segment,
                          " (make ExtensionOptions::before/after longer)");
        return out;
      }
    }
    o.kept_event_sequence = o.departure.empty() && !phase.intermediate && !phase.micro_event_ahead && phase.segment == last;
    if (o.departure.empty() && !o.kept_event_sequence)
      o.departure = phase.segment != last ? concat("ended in reference segment ", phase.segment, " of 0 .. ", last)
                                          : std::string("ended between the micro-events of a reference event");
    out.at_end = traj.final_state() - extended.state(phase.segment, T);
    out.at_times = errors_at(traj, phase_segments, extended, times);
  } catch (const std::exception& ex) {
    o.failed = true;
    o.reason = ex.what();
  }
  return out;
}

/// The nominal run's part of `report` (MonteCarloOptions::relative_to_nominal_run): its distance
/// from the reference in the output norm C, and whether the runs are measured against it (else
/// why not). Returns whether they are.
template <Scene S>
bool record_nominal_run(const MonteCarloRun& o, const RunErrors<S>& nominal, const Mat<2 * S::nq, 2 * S::nq>& C,
                        MonteCarloReport& report) {
  if (!o.failed) {
    report.nominal_run_deviation = report.nominal_run_max_deviation = (C * nominal.at_end).norm();
    for (const Vec<2 * S::nq>& e : nominal.at_times)
      if (e.allFinite()) report.nominal_run_max_deviation = std::max(report.nominal_run_max_deviation, (C * e).norm());
  }
  report.relative_to_nominal_run = !o.failed && o.kept_event_sequence;
  if (!report.relative_to_nominal_run)
    report.nominal_run_departure = o.failed ? concat("the nominal run failed: ", o.reason)
                                            : concat("the nominal run left the event sequence: ", o.departure);
  return report.relative_to_nominal_run;
}

}  // namespace detail

template <Scene S>
MonteCarloReport monte_carlo(const S& scene, const SimulationOptions& simulation,
                             const ReferenceSpreadingController<S>& controller, const ClosedLoopLinearisation<S>& cl,
                             const MonteCarloOptions<S>& options) {
  constexpr int nx = 2 * S::nq;
  using Matrix = Mat<nx, nx>;
  using State = Vec<nx>;
  SALTUS_REQUIRE(options.runs >= 1, "monte_carlo: runs must be >= 1, got ", options.runs);
  SALTUS_REQUIRE(options.size > 0 && std::isfinite(options.size), "monte_carlo: size must be > 0, got ", options.size);
  SALTUS_REQUIRE(options.scale.allFinite(), "monte_carlo: the scale must be finite");
  const LinearisedSystem<S>& ol = cl.open_loop();
  const auto& ref = ol.reference().reference();
  Matrix Lt, Lt_inv;
  detail::weight_factor<nx>(options.weight, "monte_carlo", Lt, Lt_inv);
  const Matrix C = detail::output_factor<nx>(options.output_weight, Lt, "monte_carlo");
  const double t0 = ol.t_begin(0);
  const double T = options.t_final < 0 ? ol.t_end(ol.segment_count() - 1) : options.t_final;
  SALTUS_REQUIRE(T > t0, "monte_carlo: t_final = ", T, " is not after the reference's start ", t0);
  const int last = ref.segment_at(T);
  const State x0 = ref.state(0, t0);
  // The deviation times: their reference segments and flow transitions from the segments' starts.
  const std::vector<double>& times = options.deviation_times;
  std::vector<int> time_segments;
  std::vector<Matrix> time_flows;
  for (std::size_t k = 0; k < times.size(); ++k) {
    SALTUS_REQUIRE(std::isfinite(times[k]) && times[k] > t0 && times[k] <= T && (k == 0 || times[k] > times[k - 1]),
                   "monte_carlo: deviation_times must increase within (", t0, ", ", T, "], got ", times[k],
                   " at position ", k);
    const int i = ref.segment_at(times[k]);
    time_segments.push_back(i);
    time_flows.push_back(times[k] == ol.t_end(i) ? cl.segment_transition(i)
                                                 : cl.flow_transition(i, times[k], ol.t_begin(i)));
  }

  // Perturbations and their first-order predictions, in this thread (deterministic; the
  // linearisation builds conewise pieces on demand and is not thread-safe).
  MonteCarloReport report;
  report.runs = options.runs;
  report.run.resize(options.runs);
  report.deviation_times = times;
  // The starts x0 + eps d; with keep_initial_contacts projected onto the first mode, and d the
  // projected start's deviation over eps (what the prediction and the normalisation then use).
  std::vector<State> d(options.runs), start(options.runs);
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal;
  ConstraintProjection<S> projection;
  projection.max_iterations = 20;
  for (int r = 0; r < options.runs; ++r) {
    for (int j = 0; j < nx; ++j) d[r][j] = options.scale[j] * normal(rng);
    if (options.project) d[r] = options.project(d[r]);
    start[r] = x0 + options.size * d[r];
    if (options.keep_initial_contacts) {
      projection.project(scene, ref.segments.front().mode, start[r]);
      d[r] = (start[r] - x0) / options.size;
    }
    SALTUS_REQUIRE(d[r].allFinite() && (Lt * d[r]).norm() > 0, "monte_carlo: perturbation ", r, " is zero or not finite");
    try {
      report.run[r].predicted = (C * cl.propagate(d[r], T)).norm() / (Lt * d[r]).norm();
    } catch (const SimultaneousActivation&) {
      report.run[r].predicted = std::numeric_limits<double>::quiet_NaN();
    }
    if (!times.empty())
      report.run[r].predicted_over_time =
          detail::predicted_deviations(cl, time_segments, time_flows, d[r], C, (Lt * d[r]).norm());
  }

  unsigned hw = std::thread::hardware_concurrency();
  const int threads = std::max(1, std::min(options.runs, options.threads > 0 ? options.threads : static_cast<int>(hw ? hw : 1)));
  report.threads = threads;
  // The gains' kinks as breakpoints of the plant's integration (ReferenceSpreadingController::breakpoints).
  SimulationOptions plant = simulation;
  const std::vector<double> kinks = controller.breakpoints();
  plant.breakpoints.insert(plant.breakpoints.end(), kinks.begin(), kinks.end());
  std::vector<std::unique_ptr<Simulator<S>>> simulators;
  for (int w = 0; w < threads; ++w) simulators.push_back(std::make_unique<Simulator<S>>(scene, plant));
  const auto wall = std::chrono::steady_clock::now();
  // Counts for the progress lines: atomics, so that a line never reads another worker's run.
  std::atomic<int> failed_so_far{0}, kept_so_far{0};
  // The nominal run (d = 0), against which the runs are measured (relative_to_nominal_run).
  State nominal_end = State::Zero();
  std::vector<State> nominal_errors(times.size(), State::Zero());
  if (options.relative_to_nominal_run) {
    MonteCarloRun outcome;
    const detail::RunErrors<S> nominal = detail::track_run(*simulators[0], controller, x0, t0, T, last, times, outcome);
    if (detail::record_nominal_run(outcome, nominal, C, report)) {
      nominal_end = nominal.at_end;
      nominal_errors = nominal.at_times;
    }
  }
  auto body = [&](int r, int worker) {
    MonteCarloRun& out = report.run[r];
    struct Count {  // counts this run once its result is final, however the body returns
      const MonteCarloRun& run;
      std::atomic<int>& failed;
      std::atomic<int>& kept;
      ~Count() {
        if (run.failed) ++failed;
        if (run.kept_event_sequence) ++kept;
      }
    } count{out, failed_so_far, kept_so_far};
    const detail::RunErrors<S> run = detail::track_run(*simulators[worker], controller, start[r], t0, T, last, times, out);
    if (out.failed) return;
    const double scale = (Lt * (options.size * d[r])).norm();
    out.observed = (C * (run.at_end - nominal_end)).norm() / scale;
    for (std::size_t k = 0; k < times.size(); ++k)  // a NaN error (beyond an extension) stays NaN
      out.observed_over_time.push_back((C * (run.at_times[k] - nominal_errors[k])).norm() / scale);
  };
  auto after_batch = [&](int done) {
    if (!options.progress) return;
    *options.progress << "monte carlo: " << done << "/" << options.runs << " runs, " << failed_so_far.load()
                      << " failed, " << kept_so_far.load()
                      << " kept the event sequence, "
                      << std::chrono::duration<double>(std::chrono::steady_clock::now() - wall).count() << " s ("
                      << threads << " threads)\n"
                      << std::flush;
  };
  detail::parallel_for(options.runs, threads, std::max(1, options.batch), body, after_batch);
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall).count();

  summarise_monte_carlo(report, T - t0);
  return report;
}

}  // namespace saltus
