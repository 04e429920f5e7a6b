#include "homotopy.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <ostream>
#include <sstream>
#include <string>
#include <variant>

#include "ipopt_adapter.hpp"
#include "ipopt_session.hpp"
#include "mpcc_layout.hpp"
#include "polish.hpp"
#include "progress.hpp"
#include "relaxation.hpp"
#include "solve_context.hpp"

namespace saltus::timefreezing::detail {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// sigma rounded to the nearest power of ten when within 1e-12 relative of it: repeated products
/// drift (1 * 0.1^9 = 1.0000000000000005e-9), and under the smoothing a smoothable pair's residual
/// IS sigma_k, so a schedule of decades would miss the tolerance 1e-9 by one rounding and run one
/// more, expensive step (a user's trial: 2279 of 2983 iterations spent on sigma = 1e-10).
double snap_to_decade(double sigma) {
  if (!(sigma > 0.0) || !std::isfinite(sigma)) return sigma;
  const double decade = std::pow(10.0, std::round(std::log10(sigma)));
  return std::abs(sigma - decade) <= 1e-12 * decade ? decade : sigma;
}

/// Ipopt's max_iter of a homotopy step: ipopt.max_iter unless ipopt.options sets it (a polish
/// sets its own and restores this one).
int step_max_iter(const MpccSolverOptions& o) {
  int max_iter = o.ipopt.max_iter;
  for (const IpoptOption& option : o.ipopt.options)
    if (option.name == "max_iter" && std::holds_alternative<int>(option.value)) max_iter = std::get<int>(option.value);
  return max_iter;
}

/// The homotopy's state between its steps; run() is the loop (solve.hpp, "HOMOTOPY").
class Homotopy {
 public:
  Homotopy(const Mpcc& problem, const MpccStart& start, bool with_multipliers, const MpccSolverOptions& options);
  MpccSolution run();

 private:
  void run_step(int k);
  MpccHomotopyStep solve_relaxed(int k, int retry);
  void refine(const MpccHomotopyStep& step, int k);
  void on_success(const MpccHomotopyStep& step, int k);
  bool retry_after_failure(const MpccHomotopyStep& step, int k, int retry);
  void accept(const MpccHomotopyStep& step);
  bool try_polish(int k, double sigma);
  MpccSolution finish();
  std::string message() const;

  const Clock::time_point start_time_ = Clock::now();
  const MpccSolverOptions& options_;
  MpccLayout layout_;
  RelaxedNlp relaxed_;
  Ipopt::SmartPtr<ReformulatedNlp> nlp_;
  IpoptSession session_;
  MpccSolution solution_;
  SolveContext context_;
  const bool user_multipliers_;
  const bool polish_enabled_;
  PrimalDual initial_;
  std::optional<PrimalDual> success_;  ///< the last successful step's primal-dual solution
  std::optional<PrimalDual> last_;     ///< the last iterate Ipopt returned, successful or not
  int success_index_ = -1;
  double success_sigma_ = 0.0, success_complementarity_ = 0.0, success_violation_ = 0.0;
  /// The successful step before `success_` (x and sigma), for the polish's trend rule.
  Eigen::VectorXd previous_x_;
  double previous_sigma_ = 0.0;
  std::optional<PolishResult> polished_;
  bool success_polished_ = false;  ///< the polish of the current `success_` has been tried
  double kappa_, sigma_;
  std::string stop_message_;
  bool converged_ = false;
  /// Converged, polish not succeeded, the residual above homotopy.complementarity_refinement: the
  /// homotopy goes on.
  bool refining_ = false;
  std::string refinement_end_;
  int refinement_steps_ = 0;  ///< accepted
};

Homotopy::Homotopy(const Mpcc& problem, const MpccStart& start, bool with_multipliers, const MpccSolverOptions& options)
    : options_(options),
      layout_(problem),
      relaxed_(layout_, options.homotopy.relaxation),
      nlp_(new ReformulatedNlp(layout_, relaxed_.nlp())),
      session_(options.ipopt.print_level),
      context_{options, layout_, relaxed_, session_, solution_, step_max_iter(options)},
      user_multipliers_(with_multipliers),
      polish_enabled_(options.polish.enabled && layout_.pair_count() > 0),
      kappa_(options.homotopy.kappa),
      sigma_(options.homotopy.sigma_0) {
  session_.set_number("tol", options.ipopt.tol);
  session_.set_integer("max_iter", options.ipopt.max_iter);
  for (const IpoptOption& option : MpccSolverOptions::IpoptSettings::solver_defaults()) session_.set(option);
  for (const IpoptOption& option : options.ipopt.options) session_.set(option);
  session_.initialize();

  const int n = layout_.variable_count(), m = layout_.constraint_count();
  initial_.x = start.x;
  initial_.lambda = Eigen::VectorXd::Zero(relaxed_.row_count());
  initial_.z_lower = Eigen::VectorXd::Zero(n);
  initial_.z_upper = Eigen::VectorXd::Zero(n);
  if (with_multipliers) {
    initial_.lambda.head(m) = start.constraint_multipliers;
    initial_.z_lower = start.bound_multipliers_lower;
    initial_.z_upper = start.bound_multipliers_upper;
  }
  solution_.relaxed_rows = relaxed_.row_count();
  solution_.sign_rows = relaxed_.sign_row_count();
  if (options.homotopy.relaxation == MpccSolverOptions::Relaxation::Smoothing)
    for (const ComplementarityPair& pair : problem.complementarity_pairs()) solution_.smoothed_pairs += pair.smoothable;
}

MpccSolution Homotopy::run() {
  const MpccSolverOptions::Homotopy& h = options_.homotopy;
  for (int k = 0; k < h.max_steps && (!converged_ || refining_) && stop_message_.empty(); ++k) {
    run_step(k);
    if ((!converged_ || refining_) && stop_message_.empty()) sigma_ = snap_to_decade(sigma_ * kappa_);
  }
  // The homotopy stopped on a failure: polish its last successful step if not done yet.
  if (polish_enabled_ && success_ && !success_polished_ && !converged_ && try_polish(success_index_, success_sigma_))
    converged_ = true;
  return finish();
}

/// Homotopy step k at sigma_: its solve, then its retries (slower decrease) while it fails.
void Homotopy::run_step(int k) {
  for (int retry = 0;; ++retry) {
    const MpccHomotopyStep step = solve_relaxed(k, retry);
    if (refining_) {
      refine(step, k);
      return;
    }
    if (nlp_->has_result()) last_ = nlp_->result();
    if (step.ipopt_succeeded) {
      on_success(step, k);
      return;
    }
    if (!retry_after_failure(step, k, retry)) return;
  }
}

/// One Ipopt solve of the relaxed NLP at sigma_, from the last successful step (warm: its
/// primal-dual solution) or the start; recorded in the solution and the progress.
MpccHomotopyStep Homotopy::solve_relaxed(int k, int retry) {
  const PrimalDual& from = success_ ? *success_ : initial_;
  const bool warm = options_.warm_start && (success_.has_value() || user_multipliers_);
  if (warm)
    nlp_->set_start(from.x, from.lambda, from.z_lower, from.z_upper);
  else
    nlp_->set_start(from.x);
  session_.set_string("warm_start_init_point", warm ? "yes" : "no");
  relaxed_.set_sigma(sigma_);
  nlp_->clear_result();

  const Clock::time_point step_start = Clock::now();
  const Ipopt::ApplicationReturnStatus status = session_.app->OptimizeTNLP(Ipopt::GetRawPtr(nlp_));
  session_.throw_on_setup_error(status);

  MpccHomotopyStep step;
  step.index = k;
  step.retry = retry;
  step.sigma = sigma_;
  step.ipopt_iterations = session_.iterations();
  step.ipopt_status = status_name(status);
  const Eigen::VectorXd& x = nlp_->has_result() ? nlp_->result().x : from.x;
  step.complementarity = layout_.complementarity(x);
  step.objective = layout_.problem().objective(x);
  step.constraint_violation = layout_.constraint_violation(x, &step.worst_violation);
  step.ipopt_succeeded = successful(status, step.constraint_violation, options_);
  step.seconds = seconds_since(step_start);
  solution_.ipopt_iterations += step.ipopt_iterations;
  solution_.steps.push_back(step);
  if (options_.progress)
    *options_.progress << format_step(step, options_.homotopy.relaxation == MpccSolverOptions::Relaxation::Penalty)
                       << std::flush;
  return step;
}

/// A refinement step (homotopy.complementarity_refinement) is kept only when it succeeded and
/// lowered the residual without raising the violation; else the refinement ends with the previous
/// (converged) step.
void Homotopy::refine(const MpccHomotopyStep& step, int k) {
  const MpccSolverOptions::Homotopy& h = options_.homotopy;
  std::ostringstream why;
  why.precision(3);
  const double allowed_violation = std::max(success_violation_, options_.polish.feasibility_tolerance);
  if (!step.ipopt_succeeded)
    why << "refinement ended at homotopy step " << k << " (sigma = " << sigma_ << "): Ipopt " << step.ipopt_status;
  else if (!(step.complementarity < success_complementarity_))
    why << "refinement ended at homotopy step " << k << " (sigma = " << sigma_ << "): complementarity "
        << step.complementarity << " not below " << success_complementarity_;
  else if (step.constraint_violation > allowed_violation)
    // An "acceptable" Ipopt exit may trade feasibility for the smaller residual.
    why << "refinement ended at homotopy step " << k << " (sigma = " << sigma_ << "): constraint violation "
        << step.constraint_violation << " above " << allowed_violation;
  if (!why.str().empty()) {
    refinement_end_ = why.str();
    refining_ = false;
    return;
  }
  if (nlp_->has_result()) last_ = nlp_->result();
  accept(step);
  ++refinement_steps_;
  refining_ = step.complementarity > h.complementarity_refinement;
  if (refining_ && k + 1 == h.max_steps) {
    std::ostringstream budget;
    budget.precision(3);
    budget << "refinement stopped by homotopy.max_steps = " << h.max_steps << " at complementarity "
           << step.complementarity << " > " << h.complementarity_refinement;
    refinement_end_ = budget.str();
  }
}

/// A successful step: the new successful iterate, convergence, the polish, the refinement.
void Homotopy::on_success(const MpccHomotopyStep& step, int k) {
  const MpccSolverOptions::Homotopy& h = options_.homotopy;
  accept(step);
  success_polished_ = false;
  if (step.complementarity <= h.complementarity_tolerance) converged_ = true;
  const bool last_step = converged_ || k + 1 == h.max_steps;
  if (polish_enabled_ && (step.complementarity <= options_.polish.below || last_step)) {
    success_polished_ = true;
    if (try_polish(k, sigma_)) converged_ = true;
  }
  refining_ = converged_ && !polished_ && h.complementarity_refinement > 0.0 &&
              step.complementarity > h.complementarity_refinement;
  if (refining_ && k + 1 == h.max_steps)
    refinement_end_ =
        "refinement not started: homotopy.max_steps = " + std::to_string(h.max_steps) + " reached at convergence";
}

/// A failed step: true to retry it from the last successful sigma with the slower decrease
/// kappa <- sqrt(kappa), kept for the rest of the homotopy; false (and stop_message_) when there
/// is no successful step to restart from or the retries are spent.
bool Homotopy::retry_after_failure(const MpccHomotopyStep& step, int k, int retry) {
  std::ostringstream why;
  why.precision(3);
  if (!success_) {
    why << "Ipopt failed at the first homotopy step (sigma = " << sigma_ << "): " << step.ipopt_status
        << "; no successful iterate to restart from";
    stop_message_ = why.str();
    return false;
  }
  if (retry == options_.homotopy.max_step_retries) {
    why << "Ipopt failed at homotopy step " << k << " (sigma = " << sigma_ << ") after " << retry
        << " retries, last status " << step.ipopt_status << "; the last successful step " << success_index_
        << " (sigma = " << success_sigma_ << ") had complementarity " << success_complementarity_;
    stop_message_ = why.str();
    return false;
  }
  kappa_ = std::sqrt(kappa_);
  sigma_ = snap_to_decade(kappa_ * success_sigma_);
  return true;
}

/// `last_` becomes the successful iterate; the one it replaces is kept for the polish's trend rule.
void Homotopy::accept(const MpccHomotopyStep& step) {
  if (success_) {
    previous_x_ = success_->x;
    previous_sigma_ = success_sigma_;
  }
  success_ = last_;
  success_index_ = step.index;
  success_sigma_ = step.sigma;
  success_complementarity_ = step.complementarity;
  success_violation_ = step.constraint_violation;
}

bool Homotopy::try_polish(int k, double sigma) {
  std::optional<PolishResult> result = polish_step(context_, *success_, k, sigma, previous_x_, previous_sigma_);
  if (!result) return false;
  polished_ = std::move(result);
  return true;
}

MpccSolution Homotopy::finish() {
  const PrimalDual& result = polished_ ? polished_->point : success_ ? *success_ : (last_ ? *last_ : initial_);
  const int m = layout_.constraint_count();
  solution_.polished = polished_.has_value();
  solution_.converged = converged_;
  solution_.x = result.x;
  solution_.constraint_multipliers = result.lambda.head(m);
  solution_.bound_multipliers_lower = result.z_lower;
  solution_.bound_multipliers_upper = result.z_upper;
  solution_.objective = layout_.problem().objective(result.x);
  int worst = -1;
  solution_.complementarity = layout_.complementarity(result.x, &worst);
  solution_.worst_pair = worst >= 0 && solution_.complementarity > 0.0
                             ? layout_.problem().complementarity_pairs()[static_cast<std::size_t>(worst)].name
                             : std::string();
  solution_.constraint_violation = layout_.constraint_violation(result.x);
  solution_.message = message();
  solution_.seconds = seconds_since(start_time_);
  return std::move(solution_);
}

std::string Homotopy::message() const {
  const MpccSolverOptions::Homotopy& h = options_.homotopy;
  std::ostringstream message;
  message.precision(3);
  if (polished_) {
    message << "converged: complementarity " << solution_.complementarity << " <= " << h.complementarity_tolerance
            << polished_->summary;
  } else if (converged_) {
    message << "converged: complementarity " << solution_.complementarity << " <= " << h.complementarity_tolerance
            << " at homotopy step " << success_index_ << " (sigma = " << success_sigma_ << ")";
    if (h.complementarity_refinement > 0.0)
      message << "; " << refinement_steps_ << " refinement step" << (refinement_steps_ == 1 ? "" : "s") << " accepted"
              << (refinement_end_.empty() ? "" : ", " + refinement_end_);
  } else if (!stop_message_.empty()) {
    message << stop_message_;
  } else {
    message << "not converged: complementarity " << solution_.complementarity << " > " << h.complementarity_tolerance
            << " after " << h.max_steps << " homotopy steps (last successful sigma = " << success_sigma_ << ")";
  }
  return message.str();
}

}  // namespace

MpccSolution run_homotopy(const Mpcc& problem, const MpccStart& start, bool with_multipliers,
                          const MpccSolverOptions& options) {
  return Homotopy(problem, start, with_multipliers, options).run();
}

}  // namespace saltus::timefreezing::detail
