#include <saltus/timefreezing/mpcc/mpcc_solver.hpp>

#include "relaxed_nlp.hpp"

#include <saltus/hybrid/vocabulary/errors.hpp>

#include <IpIpoptApplication.hpp>
#include <IpJournalist.hpp>
#include <IpSolveStatistics.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <limits>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>

namespace saltus::timefreezing {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string status_name(Ipopt::ApplicationReturnStatus status) {
  switch (status) {
    case Ipopt::Solve_Succeeded: return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level: return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected: return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small: return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates: return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop: return "User_Requested_Stop";
    case Ipopt::Feasible_Point_Found: return "Feasible_Point_Found";
    case Ipopt::Maximum_Iterations_Exceeded: return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed: return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation: return "Error_In_Step_Computation";
    case Ipopt::Maximum_CpuTime_Exceeded: return "Maximum_CpuTime_Exceeded";
    case Ipopt::Not_Enough_Degrees_Of_Freedom: return "Not_Enough_Degrees_Of_Freedom";
    case Ipopt::Invalid_Problem_Definition: return "Invalid_Problem_Definition";
    case Ipopt::Invalid_Option: return "Invalid_Option";
    case Ipopt::Invalid_Number_Detected: return "Invalid_Number_Detected";
    case Ipopt::Unrecoverable_Exception: return "Unrecoverable_Exception";
    case Ipopt::NonIpopt_Exception_Thrown: return "NonIpopt_Exception_Thrown";
    case Ipopt::Insufficient_Memory: return "Insufficient_Memory";
    case Ipopt::Internal_Error: return "Internal_Error";
  }
  return "Unknown_Status_" + std::to_string(static_cast<int>(status));
}

/// Collects what Ipopt writes to it (the derivative checker's verdict, Ipopt's error messages),
/// up to a size limit: a journal of its own instead of a temporary file, so nothing touches the
/// file system and concurrent solves do not share output.
class CaptureJournal : public Ipopt::Journal {
 public:
  CaptureJournal(const std::string& name, Ipopt::EJournalLevel level, std::size_t max_chars)
      : Ipopt::Journal(name, level), max_chars_(max_chars) {}
  const std::string& text() const { return text_; }

 protected:
  void PrintImpl(Ipopt::EJournalCategory, Ipopt::EJournalLevel, const char* str) override { append(str); }
  void PrintfImpl(Ipopt::EJournalCategory, Ipopt::EJournalLevel, const char* pformat, va_list ap) override {
    char buffer[512];
    va_list copy;
    va_copy(copy, ap);
    const int length = std::vsnprintf(buffer, sizeof buffer, pformat, copy);
    va_end(copy);
    if (length < 0) return;
    if (static_cast<std::size_t>(length) < sizeof buffer) {
      append(buffer);
    } else {
      std::string long_text(static_cast<std::size_t>(length) + 1, '\0');
      std::vsnprintf(long_text.data(), long_text.size(), pformat, ap);
      long_text.pop_back();
      append(long_text.c_str());
    }
  }
  void FlushBufferImpl() override {}

 private:
  void append(const char* str) {
    if (text_.size() < max_chars_) text_.append(str, std::min(std::char_traits<char>::length(str), max_chars_ - text_.size()));
  }
  std::string text_;
  std::size_t max_chars_;
};

/// An IpoptApplication that prints nothing unless print_level > 0, reads no ipopt.opt, lets the
/// problem's own exceptions through, and captures Ipopt's error messages (for our exceptions).
struct IpoptSession {
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app;
  Ipopt::SmartPtr<CaptureJournal> capture;

  explicit IpoptSession(int print_level) {
    // No console journal at print level 0: nothing reaches stdout, whatever Ipopt prints at
    // J_INSUPPRESSIBLE.
    app = new Ipopt::IpoptApplication(print_level > 0, false);
    app->RethrowNonIpoptException(true);
    capture = new CaptureJournal("saltus_capture", Ipopt::J_ERROR, 1 << 20);
    app->Jnlst()->AddJournal(Ipopt::GetRawPtr(capture));
    // The banner is printed once per process unless `sb` is set.
    set_string("sb", "yes");
    set_integer("print_level", print_level);
  }

  std::string captured() const {
    const std::string& t = capture->text();
    return t.empty() ? std::string() : "; Ipopt said: " + t;
  }
  void set_string(const std::string& name, const std::string& value) {
    SALTUS_REQUIRE(app->Options()->SetStringValue(name, value), "Ipopt rejected the option ", name, " = \"", value,
                   "\"", captured());
  }
  void set_integer(const std::string& name, int value) {
    SALTUS_REQUIRE(app->Options()->SetIntegerValue(name, value), "Ipopt rejected the option ", name, " = ", value,
                   " (integer)", captured());
  }
  void set_number(const std::string& name, double value) {
    SALTUS_REQUIRE(app->Options()->SetNumericValue(name, value), "Ipopt rejected the option ", name, " = ", value,
                   " (number)", captured());
  }
  void set(const IpoptOption& option) {
    SALTUS_REQUIRE(!option.name.empty(), "MpccSolverOptions::ipopt_options: an option has an empty name");
    if (const auto* s = std::get_if<std::string>(&option.value)) set_string(option.name, *s);
    else if (const auto* i = std::get_if<int>(&option.value)) set_integer(option.name, *i);
    else set_number(option.name, std::get<double>(option.value));
  }
  void initialize() {
    // From an empty stream: Initialize() would read ./ipopt.opt, making results depend on the
    // working directory.
    std::istringstream no_options;
    const Ipopt::ApplicationReturnStatus status = app->Initialize(no_options);
    SALTUS_REQUIRE(status == Ipopt::Solve_Succeeded, "Ipopt could not be initialised: ", status_name(status),
                   captured());
  }
  int iterations() {
    Ipopt::SmartPtr<Ipopt::SolveStatistics> statistics = app->Statistics();
    return Ipopt::IsValid(statistics) ? statistics->IterationCount() : 0;
  }
  /// Ipopt statuses that say the problem or the setup is wrong, or Ipopt broke: thrown, not
  /// reported as a failed step (a retry could not help).
  void throw_on_setup_error(Ipopt::ApplicationReturnStatus status) {
    switch (status) {
      case Ipopt::Invalid_Option:
        throw InvalidArgument("Ipopt: Invalid_Option (an option or its value was rejected)" + captured());
      case Ipopt::Not_Enough_Degrees_Of_Freedom:
        throw InvalidArgument(
            "Ipopt: Not_Enough_Degrees_Of_Freedom (more equality constraints than free variables)" + captured());
      case Ipopt::Invalid_Problem_Definition:
        throw InvalidArgument("Ipopt: Invalid_Problem_Definition" + captured());
      case Ipopt::Unrecoverable_Exception:
      case Ipopt::NonIpopt_Exception_Thrown:
      case Ipopt::Insufficient_Memory:
      case Ipopt::Internal_Error:
        throw NumericalFailure("Ipopt stopped with " + status_name(status) + captured());
      default:
        return;
    }
  }
};

bool successful(Ipopt::ApplicationReturnStatus status, double violation, const MpccSolverOptions& options) {
  if (status == Ipopt::Solve_Succeeded) return true;
  if (!options.accept_acceptable) return false;
  return status == Ipopt::Solved_To_Acceptable_Level ||
         (status == Ipopt::Search_Direction_Becomes_Too_Small && violation <= options.small_step_feasibility_tolerance);
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

detail::RelaxationKind relaxation_kind(MpccSolverOptions::Relaxation r) {
  switch (r) {
    case MpccSolverOptions::Relaxation::Smoothing: return detail::RelaxationKind::Smoothing;
    case MpccSolverOptions::Relaxation::Penalty: return detail::RelaxationKind::Penalty;
    case MpccSolverOptions::Relaxation::Scholtes: break;
  }
  return detail::RelaxationKind::Scholtes;
}

std::string format_step(const MpccHomotopyStep& s, bool penalty, bool elastic) {
  char line[320];
  std::snprintf(line, sizeof line,
                "mpcc step %3d%-10s %s %9.3e  compl %9.3e  f % .10e  viol %9.3e  iter %5d  %-34s %8.3f s", s.index,
                s.retry > 0 ? (" retry " + std::to_string(s.retry)).c_str() : "", penalty ? "rho  " : "sigma",
                penalty ? 1.0 / s.sigma : s.sigma, s.complementarity, s.objective, s.constraint_violation,
                s.ipopt_iterations, s.ipopt_status.c_str(), s.seconds);
  // A failed step says where its iterate is infeasible (the wall of a homotopy: dynamics, a path
  // row, a bound).
  char slack[48] = "";
  if (elastic) std::snprintf(slack, sizeof slack, "  slack %9.3e", s.elastic_slack);
  return std::string(line) + slack +
         (!s.ipopt_succeeded && !s.worst_violation.empty() ? "  worst: " + s.worst_violation : "") + "\n";
}

std::string format_polish(const MpccHomotopyStep& s, const std::string& label, int fixed, int eq_rows,
                          int ineq_rows, bool infeasible) {
  char line[400];
  std::snprintf(line, sizeof line,
                "mpcc polish %3d  attempt %d [%s]  G=0 %d H=0 %d biactive %d trend %d (fixed %d, rows %d =, %d >=)  "
                "compl %9.3e  f % .10e  viol %9.3e  iter %5d  %-34s %8.3f s",
                s.index, s.polish_attempt, label.c_str(), s.left_zero, s.right_zero, s.biactive, s.by_trend, fixed,
                eq_rows, ineq_rows, s.complementarity, s.objective, s.constraint_violation, s.ipopt_iterations,
                s.ipopt_status.c_str(), s.seconds);
  // The note can be long (a branch's reason to be infeasible names variables): appended as is.
  // The worst row only where it says something: not for a polish refused for its objective alone.
  return std::string(line) + (s.note.empty() ? "" : "  failed: " + s.note) +
         (infeasible && !s.worst_violation.empty() ? "  worst: " + s.worst_violation : "") + "\n";
}

void require_finite(const Eigen::VectorXd& v, const char* what, const Mpcc& problem, bool is_x) {
  for (Eigen::Index i = 0; i < v.size(); ++i)
    SALTUS_REQUIRE(std::isfinite(v[i]), what, "[", i, "]",
                   is_x ? " (" + problem.variable_name(static_cast<int>(i)) + ")" : std::string(), " = ", v[i],
                   " is not finite");
}

/// The homotopy; `start` is checked, with_multipliers says whether its multipliers are given.
MpccSolution solve_from(const Mpcc& problem, const MpccStart& start, bool with_multipliers,
                        const MpccSolverOptions& options) {
  const Clock::time_point solve_start = Clock::now();
  const bool penalty = options.relaxation == MpccSolverOptions::Relaxation::Penalty;
  Ipopt::SmartPtr<detail::RelaxedNlp> nlp = new detail::RelaxedNlp(
      problem, relaxation_kind(options.relaxation), options.elastic_infinity, options.elastic_slack_max);
  const Ipopt::SmartPtr<Ipopt::TNLP> tnlp = Ipopt::GetRawPtr(nlp);
  const int n = nlp->variable_count(), m = nlp->original_constraint_count(), m_total = nlp->total_constraint_count();

  IpoptSession session(options.print_level);
  session.set_number("tol", options.tol);
  session.set_integer("max_iter", options.max_iter);
  session.set_string("mu_strategy", options.mu_strategy);
  session.set_string("mu_oracle", options.mu_oracle);
  session.set_number("bound_relax_factor", options.bound_relax_factor);
  // Used only when warm_start_init_point = yes (set per step below).
  session.set_number("warm_start_bound_push", options.warm_start_bound_push);
  session.set_number("warm_start_bound_frac", std::min(options.warm_start_bound_push, 0.5));
  session.set_number("warm_start_slack_bound_push", options.warm_start_bound_push);
  session.set_number("warm_start_slack_bound_frac", std::min(options.warm_start_bound_push, 0.5));
  session.set_number("warm_start_mult_bound_push", options.warm_start_mult_bound_push);
  session.set_integer("mumps_mem_percent", options.mumps_mem_percent);
  for (const IpoptOption& option : options.ipopt_options) session.set(option);
  session.initialize();

  // The last successful iterate: x, all multipliers of the augmented NLP, z_L, z_U.
  struct Iterate {
    Eigen::VectorXd x, lambda, z_lower, z_upper;
    double slack = 0.0, slack_z_lower = 0.0, slack_z_upper = 0.0;  ///< the elastic slack (elastic_infinity)
  };
  const auto result_iterate = [&nlp] {
    return Iterate{nlp->result_x(),     nlp->result_lambda(),        nlp->result_z_lower(),
                   nlp->result_z_upper(), nlp->result_slack(), nlp->result_slack_z_lower(),
                   nlp->result_slack_z_upper()};
  };
  std::optional<Iterate> success;
  std::optional<Iterate> last;  // the last iterate Ipopt returned, successful or not
  int success_index = -1;
  double success_sigma = 0.0, success_complementarity = 0.0;

  const bool user_multipliers = with_multipliers;
  Iterate initial;
  initial.x = start.x;
  initial.lambda = Eigen::VectorXd::Zero(m_total);
  initial.z_lower = Eigen::VectorXd::Zero(n);
  initial.z_upper = Eigen::VectorXd::Zero(n);
  initial.slack = std::min(options.sigma_0, options.elastic_slack_max);
  if (user_multipliers) {
    initial.lambda.head(m) = start.constraint_multipliers;
    initial.z_lower = start.bound_multipliers_lower;
    initial.z_upper = start.bound_multipliers_upper;
  }

  MpccSolution solution;
  solution.relaxed_rows = m_total;
  solution.sign_rows = nlp->sign_row_count();
  solution.elastic_pairs = nlp->elastic_pair_count();
  if (options.relaxation == MpccSolverOptions::Relaxation::Smoothing)
    for (const ComplementarityPair& pair : problem.complementarity_pairs()) solution.smoothed_pairs += pair.smoothable;

  // Polishing (top of mpcc_solver.hpp): the branch NLP from a successful step's solution.
  const bool polish_enabled = options.polish && nlp->pair_count() > 0;
  int step_max_iter = options.max_iter;  // restored after a polish; ipopt_options may override it
  for (const IpoptOption& option : options.ipopt_options)
    if (option.name == "max_iter" && std::holds_alternative<int>(option.value)) step_max_iter = std::get<int>(option.value);
  std::optional<Iterate> polished;
  std::string polish_summary;
  // The successful step before `success` (x and sigma), for the trend of choose_branches.
  Eigen::VectorXd previous_x;
  double previous_sigma = 0.0;
  // One attempt of a polish: the branch NLP with the branches zero_side from the step's
  // solution `from`; `step` comes with index, sigma, the counts of choose_branches and the
  // attempt's identity, and is completed and recorded here. True when the attempt is accepted.
  auto run_branch = [&](const Iterate& from, double step_sigma, const std::vector<int>& zero_side,
                            MpccHomotopyStep step, const std::string& label) {
    const Clock::time_point polish_start = Clock::now();
    for (int z : zero_side) ++(z != 0 ? step.right_zero : step.left_zero);
    Ipopt::SmartPtr<detail::BranchNlp> branch = new detail::BranchNlp(*nlp, zero_side);
    std::ostringstream note;
    note.precision(3);
    Ipopt::ApplicationReturnStatus status = Ipopt::Solve_Succeeded;
    bool solved = false;
    if (branch->infeasible()) {
      step.ipopt_status = "Not_Solved";
      note << "branch infeasible by its bounds: " << branch->why();
    } else {
      branch->set_start(from.x, from.lambda, from.z_lower, from.z_upper, step_sigma);
      session.set_string("warm_start_init_point", options.warm_start ? "yes" : "no");
      session.set_integer("max_iter", options.polish_max_iter);
      status = session.app->OptimizeTNLP(Ipopt::GetRawPtr(branch));
      session.set_integer("max_iter", step_max_iter);
      // A branch with more equalities than free variables, or one Ipopt refuses, is a failed
      // guess, not a wrong problem statement.
      if (status != Ipopt::Not_Enough_Degrees_Of_Freedom && status != Ipopt::Invalid_Problem_Definition)
        session.throw_on_setup_error(status);
      step.ipopt_iterations = session.iterations();
      step.ipopt_status = status_name(status);
      solved = branch->has_result();
    }
    const Eigen::VectorXd& x = solved ? branch->result_x() : from.x;
    step.complementarity = nlp->complementarity(x);
    step.objective = problem.objective(x);
    step.constraint_violation = nlp->constraint_violation(x, &step.worst_violation);
    if (!branch->infeasible()) {
      solved = solved && successful(status, step.constraint_violation, options);
      // The relaxed optimum lies below the MPCC's by about sum_j w_j |G_j H_j| (the pairs'
      // weights in the relaxed Lagrangian times the relaxation the polish removes): allowed,
      // twice over, plus the margin.
      const double from_objective = problem.objective(from.x);
      double expected_increase = 0.0;
      for (int j = 0; j < nlp->pair_count(); ++j)
        expected_increase += std::abs(nlp->pair_weight(from.lambda, j, step_sigma) * nlp->side_value(2 * j, from.x) *
                                      nlp->side_value(2 * j + 1, from.x));
      const double objective_limit = from_objective + 2.0 * expected_increase +
                                     options.polish_objective_increase * std::max(1.0, std::abs(from_objective));
      const bool objective_ok = step.objective <= objective_limit;  // false for NaN
      step.ipopt_succeeded = solved && step.constraint_violation <= options.polish_feasibility_tolerance &&
                             step.complementarity <= options.complementarity_tolerance && objective_ok;
      if (!solved)
        note << "Ipopt: " << step.ipopt_status;
      else if (step.constraint_violation > options.polish_feasibility_tolerance)
        note << "constraint violation " << step.constraint_violation << " > " << options.polish_feasibility_tolerance;
      else if (step.complementarity > options.complementarity_tolerance)
        note << "complementarity " << step.complementarity << " > " << options.complementarity_tolerance;
      else if (!objective_ok)
        note << "objective " << step.objective << " > " << objective_limit << " (the step's " << from_objective
             << " + polish_objective_increase)";
    }
    step.note = note.str();
    step.seconds = seconds_since(polish_start);
    solution.ipopt_iterations += step.ipopt_iterations;
    solution.steps.push_back(step);
    if (options.progress)
      *options.progress << format_polish(step, label, branch->fixed_variable_count(), branch->equality_row_count(),
                                         branch->inequality_row_count(),
                                         step.constraint_violation > options.polish_feasibility_tolerance)
                        << std::flush;
    if (!step.ipopt_succeeded) return false;
    polished = Iterate{branch->result_x(), branch->result_lambda(), branch->result_z_lower(),
                       branch->result_z_upper()};
    std::ostringstream summary;
    summary << "; polished from homotopy step " << step.index << " (sigma = " << step_sigma
            << ") by a branch NLP with " << step.left_zero << " pairs G = 0, " << step.right_zero << " pairs H = 0 ("
            << step.biactive << " biactive), " << label;
    polish_summary = summary.str();
    return true;
  };
  // The polish of a successful step: the first guess of choose_branches, then the fallback
  // (top of mpcc_solver.hpp): the biactive pairs flipped together, then one at a time.
  auto try_polish = [&](const Iterate& from, int k, double step_sigma) {
    MpccHomotopyStep base;
    base.index = k;
    base.sigma = step_sigma;
    base.polish = true;
    const bool trend = previous_x.size() > 0 && previous_sigma > step_sigma;
    std::vector<int> biactive_pairs;
    const std::vector<int> guess =
        nlp->choose_branches(from.x, std::sqrt(options.complementarity_tolerance), &base.biactive,
                             trend ? &previous_x : nullptr, trend ? step_sigma / previous_sigma : 0.1, &base.by_trend,
                             &biactive_pairs);
    if (run_branch(from, step_sigma, guess, base, "first guess")) return true;
    const int n_biactive = static_cast<int>(biactive_pairs.size());
    if (!options.polish_fallback || n_biactive == 0) return false;
    std::vector<int> zero_side = guess;
    for (int j : biactive_pairs) zero_side[static_cast<std::size_t>(j)] ^= 1;
    MpccHomotopyStep step = base;
    step.polish_attempt = 1;
    step.flipped = n_biactive;
    if (run_branch(from, step_sigma, zero_side, step, "biactive flipped (" + std::to_string(n_biactive) + ")"))
      return true;
    // One biactive pair alone: with a single one, that was the attempt above.
    if (n_biactive < 2 || n_biactive > options.polish_single_flip_max_biactive) return false;
    const int flips = std::min(n_biactive, options.polish_single_flips);
    for (int f = 0; f < flips; ++f) {
      const int j = biactive_pairs[static_cast<std::size_t>(f)];
      zero_side = guess;
      zero_side[static_cast<std::size_t>(j)] ^= 1;
      step = base;
      step.polish_attempt = 2 + f;
      step.flipped = 1;
      step.flipped_pair = j;
      if (run_branch(from, step_sigma, zero_side, step,
                         "flipped " + problem.complementarity_pairs()[static_cast<std::size_t>(j)].name))
        return true;
    }
    return false;
  };
  bool success_polished = false;  // the polish of the current `success` has been tried

  double kappa = options.kappa;
  double sigma = options.sigma_0;
  std::string stop_message;
  bool converged = false;
  // Converged, polish not succeeded, the residual above options.complementarity_refinement: the
  // homotopy goes on (MpccSolverOptions::complementarity_refinement).
  bool refining = false;
  std::string refinement_end;
  double success_violation = 0.0;  // of `success` (a refinement step may not exceed it)
  int refinement_steps = 0;        // accepted
  // `last` becomes the successful iterate; the one it replaces is kept for the polish's trend rule.
  const auto accept = [&](const MpccHomotopyStep& step) {
    if (success) {
      previous_x = success->x;
      previous_sigma = success_sigma;
    }
    success = last;
    success_index = step.index;
    success_sigma = step.sigma;
    success_complementarity = step.complementarity;
    success_violation = step.constraint_violation;
  };

  for (int k = 0; k < options.max_homotopy_steps && (!converged || refining) && stop_message.empty(); ++k) {
    for (int retry = 0;; ++retry) {
      const Iterate& from = success ? *success : initial;
      const bool warm = (options.warm_start || sigma <= options.warm_start_below) &&
                        (success.has_value() || user_multipliers);
      if (warm) nlp->set_start(from.x, from.lambda, from.z_lower, from.z_upper);
      else nlp->set_start(from.x);
      nlp->set_slack_start(from.slack, from.slack_z_lower, from.slack_z_upper);
      session.set_string("warm_start_init_point", warm ? "yes" : "no");
      nlp->set_sigma(sigma);
      nlp->clear_result();

      const Clock::time_point step_start = Clock::now();
      const Ipopt::ApplicationReturnStatus status = session.app->OptimizeTNLP(tnlp);
      session.throw_on_setup_error(status);

      MpccHomotopyStep step;
      step.index = k;
      step.retry = retry;
      step.sigma = sigma;
      step.ipopt_iterations = session.iterations();
      step.ipopt_status = status_name(status);
      const Eigen::VectorXd& x = nlp->has_result() ? nlp->result_x() : from.x;
      step.complementarity = nlp->complementarity(x);
      step.objective = problem.objective(x);
      step.elastic_slack = nlp->has_result() ? nlp->result_slack() : from.slack;
      step.constraint_violation = nlp->constraint_violation(x, &step.worst_violation);
      step.ipopt_succeeded = successful(status, step.constraint_violation, options);
      step.seconds = seconds_since(step_start);
      solution.ipopt_iterations += step.ipopt_iterations;
      solution.steps.push_back(step);
      if (options.progress) *options.progress << format_step(step, penalty, nlp->elastic()) << std::flush;

      if (refining) {
        // A refinement step is kept only when it succeeded and lowered the residual; else the
        // refinement ends with the previous (converged) step.
        std::ostringstream why;
        why.precision(3);
        const double allowed_violation = std::max(success_violation, options.polish_feasibility_tolerance);
        if (!step.ipopt_succeeded)
          why << "refinement ended at homotopy step " << k << " (sigma = " << sigma << "): Ipopt " << step.ipopt_status;
        else if (!(step.complementarity < success_complementarity))
          why << "refinement ended at homotopy step " << k << " (sigma = " << sigma << "): complementarity "
              << step.complementarity << " not below " << success_complementarity;
        else if (step.constraint_violation > allowed_violation)
          // An "acceptable" Ipopt exit may trade feasibility for the smaller residual.
          why << "refinement ended at homotopy step " << k << " (sigma = " << sigma << "): constraint violation "
              << step.constraint_violation << " above " << allowed_violation;
        if (!why.str().empty()) {
          refinement_end = why.str();
          refining = false;
          break;
        }
        if (nlp->has_result()) last = result_iterate();
        accept(step);
        ++refinement_steps;
        refining = step.complementarity > options.complementarity_refinement;
        if (refining && k + 1 == options.max_homotopy_steps) {
          std::ostringstream budget;
          budget.precision(3);
          budget << "refinement stopped by max_homotopy_steps = " << options.max_homotopy_steps << " at complementarity "
                 << step.complementarity << " > " << options.complementarity_refinement;
          refinement_end = budget.str();
        }
        break;
      }
      if (nlp->has_result()) last = result_iterate();
      if (step.ipopt_succeeded) {
        accept(step);
        success_polished = false;
        // A cheap step undoes one retry's slow-down (MpccSolverOptions::kappa_recovery_iterations).
        // A retry's own success does not count: it only says that the shorter step was easy.
        if (options.kappa_recovery_iterations > 0 && retry == 0 &&
            step.ipopt_iterations <= options.kappa_recovery_iterations && kappa > options.kappa)
          kappa = std::max(kappa * kappa, options.kappa);
        if (step.complementarity <= options.complementarity_tolerance) converged = true;
        const bool last_step = converged || k + 1 == options.max_homotopy_steps;
        if (polish_enabled && (step.complementarity <= options.polish_below || last_step)) {
          success_polished = true;
          if (try_polish(*success, k, sigma)) converged = true;
        }
        refining = converged && !polished && options.complementarity_refinement > 0.0 &&
                   step.complementarity > options.complementarity_refinement;
        if (refining && k + 1 == options.max_homotopy_steps)
          refinement_end = "refinement not started: max_homotopy_steps = " + std::to_string(options.max_homotopy_steps) +
                           " reached at convergence";
        break;
      }
      std::ostringstream why;
      why.precision(3);
      if (!success) {
        why << "Ipopt failed at the first homotopy step (sigma = " << sigma << "): " << step.ipopt_status
            << "; no successful iterate to restart from";
        stop_message = why.str();
        break;
      }
      if (retry == options.max_step_retries) {
        why << "Ipopt failed at homotopy step " << k << " (sigma = " << sigma << ") after " << retry
            << " retries, last status " << step.ipopt_status << "; the last successful step " << success_index
            << " (sigma = " << success_sigma << ") had complementarity " << success_complementarity;
        stop_message = why.str();
        break;
      }
      // Slower decrease from the last successful sigma, kept for the rest of the homotopy.
      kappa = std::sqrt(kappa);
      sigma = snap_to_decade(kappa * success_sigma);
    }
    if ((!converged || refining) && stop_message.empty()) sigma = snap_to_decade(sigma * kappa);
  }

  // The homotopy stopped on a failure: polish its last successful step if not done yet.
  if (polish_enabled && success && !success_polished && !converged && try_polish(*success, success_index, success_sigma))
    converged = true;

  const Iterate& result = polished ? *polished : success ? *success : (last ? *last : initial);
  solution.polished = polished.has_value();
  solution.converged = converged;
  solution.x = result.x;
  solution.constraint_multipliers = result.lambda.head(m);
  solution.bound_multipliers_lower = result.z_lower;
  solution.bound_multipliers_upper = result.z_upper;
  solution.objective = problem.objective(result.x);
  int worst = -1;
  solution.complementarity = nlp->complementarity(result.x, &worst);
  solution.worst_pair =
      worst >= 0 && solution.complementarity > 0.0 ? problem.complementarity_pairs()[worst].name : std::string();
  solution.constraint_violation = nlp->constraint_violation(result.x);
  std::ostringstream message;
  message.precision(3);
  if (polished) {
    message << "converged: complementarity " << solution.complementarity << " <= "
            << options.complementarity_tolerance << polish_summary;
  } else if (converged) {
    message << "converged: complementarity " << solution.complementarity
            << " <= " << options.complementarity_tolerance << " at homotopy step " << success_index
            << " (sigma = " << success_sigma << ")";
    if (options.complementarity_refinement > 0.0)
      message << "; " << refinement_steps << " refinement step" << (refinement_steps == 1 ? "" : "s") << " accepted"
              << (refinement_end.empty() ? "" : ", " + refinement_end);
  } else if (!stop_message.empty()) {
    message << stop_message;
  } else {
    message << "not converged: complementarity " << solution.complementarity << " > "
            << options.complementarity_tolerance << " after " << options.max_homotopy_steps
            << " homotopy steps (last successful sigma = " << success_sigma << ")";
  }
  solution.message = message.str();
  solution.seconds = seconds_since(solve_start);
  return solution;
}

}  // namespace

void MpccSolverOptions::validate() const {
  SALTUS_REQUIRE(std::isfinite(sigma_0) && sigma_0 > 0.0, "MpccSolverOptions::sigma_0 must be > 0 and finite, got ",
                 sigma_0);
  SALTUS_REQUIRE(kappa > 0.0 && kappa < 1.0, "MpccSolverOptions::kappa must be in (0, 1), got ", kappa);
  SALTUS_REQUIRE(!(elastic_infinity && relaxation == Relaxation::Penalty),
                 "MpccSolverOptions::elastic_infinity needs the Scholtes or Smoothing relaxation (Penalty has no "
                 "relaxation rows to hold the slack)");
  SALTUS_REQUIRE(elastic_slack_max > 0.0 && std::isfinite(elastic_slack_max),
                 "MpccSolverOptions::elastic_slack_max must be > 0 and finite, got ", elastic_slack_max);
  SALTUS_REQUIRE(complementarity_tolerance >= 0.0 && std::isfinite(complementarity_tolerance),
                 "MpccSolverOptions::complementarity_tolerance must be >= 0 and finite, got ",
                 complementarity_tolerance);
  SALTUS_REQUIRE(complementarity_refinement >= 0.0 && complementarity_refinement <= complementarity_tolerance,
                 "MpccSolverOptions::complementarity_refinement must be in [0, complementarity_tolerance = ",
                 complementarity_tolerance, "], got ", complementarity_refinement);
  SALTUS_REQUIRE(max_homotopy_steps >= 1, "MpccSolverOptions::max_homotopy_steps must be >= 1, got ",
                 max_homotopy_steps);
  SALTUS_REQUIRE(max_step_retries >= 0, "MpccSolverOptions::max_step_retries must be >= 0, got ", max_step_retries);
  SALTUS_REQUIRE(kappa_recovery_iterations >= 0, "MpccSolverOptions::kappa_recovery_iterations must be >= 0, got ",
                 kappa_recovery_iterations);
  SALTUS_REQUIRE(tol > 0.0 && std::isfinite(tol), "MpccSolverOptions::tol must be > 0 and finite, got ", tol);
  SALTUS_REQUIRE(max_iter >= 0, "MpccSolverOptions::max_iter must be >= 0, got ", max_iter);
  SALTUS_REQUIRE(print_level >= 0 && print_level <= 12, "MpccSolverOptions::print_level must be in [0, 12], got ",
                 print_level);
  SALTUS_REQUIRE(small_step_feasibility_tolerance >= 0.0,
                 "MpccSolverOptions::small_step_feasibility_tolerance must be >= 0, got ",
                 small_step_feasibility_tolerance);
  SALTUS_REQUIRE(bound_relax_factor >= 0.0 && std::isfinite(bound_relax_factor),
                 "MpccSolverOptions::bound_relax_factor must be >= 0 and finite, got ", bound_relax_factor);
  SALTUS_REQUIRE(warm_start_bound_push > 0.0 && std::isfinite(warm_start_bound_push),
                 "MpccSolverOptions::warm_start_bound_push must be > 0 and finite, got ", warm_start_bound_push);
  SALTUS_REQUIRE(warm_start_below >= 0.0 && std::isfinite(warm_start_below),
                 "MpccSolverOptions::warm_start_below must be >= 0 and finite, got ", warm_start_below);
  SALTUS_REQUIRE(warm_start_mult_bound_push > 0.0 && std::isfinite(warm_start_mult_bound_push),
                 "MpccSolverOptions::warm_start_mult_bound_push must be > 0 and finite, got ",
                 warm_start_mult_bound_push);
  SALTUS_REQUIRE(mumps_mem_percent >= 0, "MpccSolverOptions::mumps_mem_percent must be >= 0, got ", mumps_mem_percent);
  SALTUS_REQUIRE(polish_single_flips >= 0, "MpccSolverOptions::polish_single_flips must be >= 0, got ",
                 polish_single_flips);
  SALTUS_REQUIRE(polish_single_flip_max_biactive >= 0,
                 "MpccSolverOptions::polish_single_flip_max_biactive must be >= 0, got ",
                 polish_single_flip_max_biactive);
  SALTUS_REQUIRE(polish_max_iter >= 0, "MpccSolverOptions::polish_max_iter must be >= 0, got ", polish_max_iter);
  SALTUS_REQUIRE(polish_objective_increase >= 0.0 && std::isfinite(polish_objective_increase),
                 "MpccSolverOptions::polish_objective_increase must be >= 0 and finite, got ",
                 polish_objective_increase);
  SALTUS_REQUIRE(polish_below >= 0.0 && std::isfinite(polish_below),
                 "MpccSolverOptions::polish_below must be >= 0 and finite, got ", polish_below);
  SALTUS_REQUIRE(polish_feasibility_tolerance >= 0.0 && std::isfinite(polish_feasibility_tolerance),
                 "MpccSolverOptions::polish_feasibility_tolerance must be >= 0 and finite, got ",
                 polish_feasibility_tolerance);
  for (const IpoptOption& option : ipopt_options)
    SALTUS_REQUIRE(!option.name.empty(), "MpccSolverOptions::ipopt_options: an option has an empty name");
}

void validate_problem(const Mpcc& problem) {
  const int n = problem.variable_count(), m = problem.constraint_count();
  SALTUS_REQUIRE(n >= 1, "Mpcc: variable_count() must be >= 1, got ", n);
  SALTUS_REQUIRE(m >= 0, "Mpcc: constraint_count() must be >= 0, got ", m);
  constexpr double inf = std::numeric_limits<double>::infinity();
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  // NaN-filled: an implementation that leaves an entry unset is caught as a NaN bound.
  Eigen::VectorXd x_lower = Eigen::VectorXd::Constant(n, nan), x_upper = x_lower;
  Eigen::VectorXd g_lower = Eigen::VectorXd::Constant(m, nan), g_upper = g_lower;
  problem.bounds(x_lower, x_upper, g_lower, g_upper);
  for (int i = 0; i < n; ++i) {
    const std::string name = problem.variable_name(i);
    SALTUS_REQUIRE(!std::isnan(x_lower[i]) && !std::isnan(x_upper[i]), "Mpcc: NaN bound of variable ", i, " (",
                   name, "): [", x_lower[i], ", ", x_upper[i], "]");
    SALTUS_REQUIRE(x_lower[i] <= x_upper[i], "Mpcc: lower bound > upper bound of variable ", i, " (", name, "): ",
                   x_lower[i], " > ", x_upper[i]);
    SALTUS_REQUIRE(x_lower[i] < inf && x_upper[i] > -inf, "Mpcc: infinite bounds of variable ", i, " (", name,
                   ") leave no value: [", x_lower[i], ", ", x_upper[i], "]");
  }
  for (int j = 0; j < m; ++j) {
    const std::string name = problem.constraint_name(j);
    SALTUS_REQUIRE(!std::isnan(g_lower[j]) && !std::isnan(g_upper[j]), "Mpcc: NaN bound of constraint ", j, " (",
                   name, "): [", g_lower[j], ", ", g_upper[j], "]");
    SALTUS_REQUIRE(g_lower[j] <= g_upper[j], "Mpcc: lower bound > upper bound of constraint ", j, " (", name,
                   "): ", g_lower[j], " > ", g_upper[j]);
    SALTUS_REQUIRE(g_lower[j] < inf && g_upper[j] > -inf, "Mpcc: infinite bounds of constraint ", j, " (", name,
                   ") leave no value: [", g_lower[j], ", ", g_upper[j], "]");
  }
  Eigen::VectorXd x0 = Eigen::VectorXd::Constant(n, nan);
  problem.initial_point(x0);
  for (int i = 0; i < n; ++i)
    SALTUS_REQUIRE(std::isfinite(x0[i]), "Mpcc: initial point of variable ", i, " (", problem.variable_name(i),
                   ") is not finite: ", x0[i]);

  const std::vector<SparseEntry>& jac = problem.jacobian_structure();
  for (std::size_t e = 0; e < jac.size(); ++e)
    SALTUS_REQUIRE(jac[e].row >= 0 && jac[e].row < m && jac[e].col >= 0 && jac[e].col < n,
                   "Mpcc: jacobian_structure() entry ", e, " (", jac[e].row, ", ", jac[e].col,
                   ") is out of range for a ", m, " x ", n, " Jacobian");
  const std::vector<SparseEntry>& hess = problem.hessian_structure();
  for (std::size_t e = 0; e < hess.size(); ++e) {
    SALTUS_REQUIRE(hess[e].row >= 0 && hess[e].row < n && hess[e].col >= 0 && hess[e].col < n,
                   "Mpcc: hessian_structure() entry ", e, " (", hess[e].row, ", ", hess[e].col,
                   ") is out of range for a ", n, " x ", n, " Hessian");
    SALTUS_REQUIRE(hess[e].row >= hess[e].col, "Mpcc: hessian_structure() entry ", e, " (", hess[e].row, ", ",
                   hess[e].col, ") is above the diagonal: the structure lists the lower triangle only (row >= column)");
  }

  const std::vector<ComplementarityPair>& pairs = problem.complementarity_pairs();
  for (std::size_t j = 0; j < pairs.size(); ++j) {
    for (int side = 0; side < 2; ++side) {
      const AffineExpression& e = side == 0 ? pairs[j].left : pairs[j].right;
      const char* which = side == 0 ? "left" : "right";
      SALTUS_REQUIRE(!e.terms.empty(), "Mpcc: complementarity pair ", j, " (", pairs[j].name, "): the ", which,
                     " side has no variable (a constant side is not a complementarity constraint)");
      SALTUS_REQUIRE(std::isfinite(e.constant), "Mpcc: complementarity pair ", j, " (", pairs[j].name, "): the ",
                     which, " side's constant is not finite: ", e.constant);
      std::set<int> seen;
      for (const auto& [i, a] : e.terms) {
        SALTUS_REQUIRE(i >= 0 && i < n, "Mpcc: complementarity pair ", j, " (", pairs[j].name, "): the ", which,
                       " side has the variable index ", i, ", out of range for ", n, " variables");
        SALTUS_REQUIRE(std::isfinite(a), "Mpcc: complementarity pair ", j, " (", pairs[j].name, "): the ", which,
                       " side's coefficient of ", problem.variable_name(i), " is not finite: ", a);
        SALTUS_REQUIRE(seen.insert(i).second, "Mpcc: complementarity pair ", j, " (", pairs[j].name, "): the ",
                       which, " side lists the variable ", i, " (", problem.variable_name(i),
                       ") twice (each variable at most once per side)");
      }
    }
  }
}

MpccSolution solve_mpcc(const Mpcc& problem, const MpccSolverOptions& options) {
  validate_problem(problem);
  MpccStart start;
  start.x.resize(problem.variable_count());
  problem.initial_point(start.x);
  return solve_mpcc(problem, start, options);
}

MpccSolution solve_mpcc(const Mpcc& problem, const MpccStart& start, const MpccSolverOptions& options) {
  options.validate();
  validate_problem(problem);
  const Eigen::Index n = problem.variable_count(), m = problem.constraint_count();
  SALTUS_REQUIRE(start.x.size() == n, "MpccStart::x: expected size ", n, ", got ", start.x.size());
  require_finite(start.x, "MpccStart::x", problem, true);
  const bool any_multipliers = start.constraint_multipliers.size() > 0 || start.bound_multipliers_lower.size() > 0 ||
                               start.bound_multipliers_upper.size() > 0;
  if (any_multipliers) {
    SALTUS_REQUIRE(start.constraint_multipliers.size() == m, "MpccStart::constraint_multipliers: expected size ", m,
                   " (or all multipliers empty), got ", start.constraint_multipliers.size());
    SALTUS_REQUIRE(start.bound_multipliers_lower.size() == n, "MpccStart::bound_multipliers_lower: expected size ", n,
                   " (or all multipliers empty), got ", start.bound_multipliers_lower.size());
    SALTUS_REQUIRE(start.bound_multipliers_upper.size() == n, "MpccStart::bound_multipliers_upper: expected size ", n,
                   " (or all multipliers empty), got ", start.bound_multipliers_upper.size());
    require_finite(start.constraint_multipliers, "MpccStart::constraint_multipliers", problem, false);
    require_finite(start.bound_multipliers_lower, "MpccStart::bound_multipliers_lower", problem, true);
    require_finite(start.bound_multipliers_upper, "MpccStart::bound_multipliers_upper", problem, true);
    for (Eigen::Index i = 0; i < n; ++i)
      SALTUS_REQUIRE(start.bound_multipliers_lower[i] >= 0.0 && start.bound_multipliers_upper[i] >= 0.0,
                     "MpccStart: bound multipliers must be >= 0; variable ", i, " (",
                     problem.variable_name(static_cast<int>(i)), ") has z_L = ", start.bound_multipliers_lower[i],
                     ", z_U = ", start.bound_multipliers_upper[i]);
  }
  return solve_from(problem, start, any_multipliers, options);
}

DerivativeCheckReport check_derivatives(const Mpcc& problem, const Eigen::VectorXd& x, double perturbation,
                                        double tolerance, bool elastic_slack) {
  validate_problem(problem);
  SALTUS_REQUIRE(perturbation > 0.0 && std::isfinite(perturbation),
                 "check_derivatives: perturbation must be > 0 and finite, got ", perturbation);
  SALTUS_REQUIRE(tolerance > 0.0 && std::isfinite(tolerance), "check_derivatives: tolerance must be > 0 and finite, got ",
                 tolerance);
  Ipopt::SmartPtr<detail::RelaxedNlp> nlp =
      new detail::RelaxedNlp(problem, detail::RelaxationKind::Scholtes, elastic_slack, 10.0);
  const Ipopt::SmartPtr<Ipopt::TNLP> tnlp = Ipopt::GetRawPtr(nlp);
  SALTUS_REQUIRE(x.size() == nlp->variable_count(), "check_derivatives: x: expected size ", nlp->variable_count(),
                 ", got ", x.size());
  require_finite(x, "check_derivatives: x", problem, true);
  for (Eigen::Index i = 0; i < x.size(); ++i)
    SALTUS_REQUIRE(x[i] >= nlp->x_lower()[i] && x[i] <= nlp->x_upper()[i], "check_derivatives: x[", i, "] (",
                   problem.variable_name(static_cast<int>(i)), ") = ", x[i], " is outside its bounds [",
                   nlp->x_lower()[i], ", ", nlp->x_upper()[i], "] (Ipopt would check elsewhere)");
  nlp->set_sigma(1.0);
  nlp->set_start(x);
  nlp->set_slack_start(0.5, 0.0, 0.0);

  IpoptSession session(0);
  // The checker prints its flagged entries at J_WARNING and its verdict at J_SUMMARY or
  // J_WARNING, all in category J_NLP (IpTNLPAdapter.cpp, CheckDerivatives, 3.11.9).
  session.capture->SetPrintLevel(Ipopt::J_NLP, Ipopt::J_WARNING);
  session.set_string("derivative_test", "second-order");
  session.set_number("derivative_test_perturbation", perturbation);
  session.set_number("derivative_test_tol", tolerance);
  session.set_string("derivative_test_print_all", "no");
  // Without this Ipopt checks at a random point within 10 of x (clipped to the bounds).
  session.set_number("point_perturbation_radius", 0.0);
  session.set_integer("max_iter", 0);
  session.set_number("bound_relax_factor", 0.0);
  session.initialize();
  const Ipopt::ApplicationReturnStatus status = session.app->OptimizeTNLP(tnlp);

  DerivativeCheckReport report;
  report.output = session.capture->text();
  report.ipopt_status = status_name(status);
  // Verdicts as printed by TNLPAdapter::CheckDerivatives (3.11.9):
  //   "\nNo errors detected by derivative checker.\n\n"
  //   "\nDerivative checker detected %d error(s).\n\n"
  static const std::string none = "No errors detected by derivative checker.";
  static const std::string some = "Derivative checker detected ";
  if (report.output.find(none) != std::string::npos) {
    report.errors = 0;
    return report;
  }
  const std::size_t at = report.output.find(some);
  SALTUS_CHECK_NUMERICS(at != std::string::npos, "check_derivatives: Ipopt's derivative checker gave no verdict (status ",
                        report.ipopt_status, "); Ipopt said: ", report.output);
  report.errors = std::atoi(report.output.c_str() + at + some.size());
  return report;
}

}  // namespace saltus::timefreezing
