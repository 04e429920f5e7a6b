#include "ipopt_session.hpp"

#include <IpSolveStatistics.hpp>
#include <algorithm>
#include <cstdio>
#include <saltus/hybrid/vocabulary/errors.hpp>
#include <sstream>
#include <variant>

namespace saltus::timefreezing::detail {

std::string status_name(Ipopt::ApplicationReturnStatus status) {
  switch (status) {
    case Ipopt::Solve_Succeeded:
      return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level:
      return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected:
      return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small:
      return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates:
      return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop:
      return "User_Requested_Stop";
    case Ipopt::Feasible_Point_Found:
      return "Feasible_Point_Found";
    case Ipopt::Maximum_Iterations_Exceeded:
      return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed:
      return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation:
      return "Error_In_Step_Computation";
    case Ipopt::Maximum_CpuTime_Exceeded:
      return "Maximum_CpuTime_Exceeded";
    case Ipopt::Not_Enough_Degrees_Of_Freedom:
      return "Not_Enough_Degrees_Of_Freedom";
    case Ipopt::Invalid_Problem_Definition:
      return "Invalid_Problem_Definition";
    case Ipopt::Invalid_Option:
      return "Invalid_Option";
    case Ipopt::Invalid_Number_Detected:
      return "Invalid_Number_Detected";
    case Ipopt::Unrecoverable_Exception:
      return "Unrecoverable_Exception";
    case Ipopt::NonIpopt_Exception_Thrown:
      return "NonIpopt_Exception_Thrown";
    case Ipopt::Insufficient_Memory:
      return "Insufficient_Memory";
    case Ipopt::Internal_Error:
      return "Internal_Error";
  }
  return "Unknown_Status_" + std::to_string(static_cast<int>(status));
}

void CaptureJournal::PrintfImpl(Ipopt::EJournalCategory, Ipopt::EJournalLevel, const char* pformat, va_list ap) {
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

void CaptureJournal::append(const char* str) {
  if (text_.size() < max_chars_)
    text_.append(str, std::min(std::char_traits<char>::length(str), max_chars_ - text_.size()));
}

IpoptSession::IpoptSession(int print_level) {
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

std::string IpoptSession::captured() const {
  const std::string& t = capture->text();
  return t.empty() ? std::string() : "; Ipopt said: " + t;
}

void IpoptSession::set_string(const std::string& name, const std::string& value) {
  SALTUS_REQUIRE(app->Options()->SetStringValue(name, value), "Ipopt rejected the option ", name, " = \"", value, "\"",
                 captured());
}

void IpoptSession::set_integer(const std::string& name, int value) {
  SALTUS_REQUIRE(app->Options()->SetIntegerValue(name, value), "Ipopt rejected the option ", name, " = ", value,
                 " (integer)", captured());
}

void IpoptSession::set_number(const std::string& name, double value) {
  SALTUS_REQUIRE(app->Options()->SetNumericValue(name, value), "Ipopt rejected the option ", name, " = ", value,
                 " (number)", captured());
}

void IpoptSession::set(const IpoptOption& option) {
  SALTUS_REQUIRE(!option.name.empty(), "MpccSolverOptions::ipopt.options: an option has an empty name");
  if (const auto* s = std::get_if<std::string>(&option.value))
    set_string(option.name, *s);
  else if (const auto* i = std::get_if<int>(&option.value))
    set_integer(option.name, *i);
  else
    set_number(option.name, std::get<double>(option.value));
}

void IpoptSession::initialize() {
  // From an empty stream: Initialize() would read ./ipopt.opt, making results depend on the
  // working directory.
  std::istringstream no_options;
  const Ipopt::ApplicationReturnStatus status = app->Initialize(no_options);
  SALTUS_REQUIRE(status == Ipopt::Solve_Succeeded, "Ipopt could not be initialised: ", status_name(status), captured());
}

int IpoptSession::iterations() {
  Ipopt::SmartPtr<Ipopt::SolveStatistics> statistics = app->Statistics();
  return Ipopt::IsValid(statistics) ? statistics->IterationCount() : 0;
}

void IpoptSession::throw_on_setup_error(Ipopt::ApplicationReturnStatus status) {
  switch (status) {
    case Ipopt::Invalid_Option:
      throw InvalidArgument("Ipopt: Invalid_Option (an option or its value was rejected)" + captured());
    case Ipopt::Not_Enough_Degrees_Of_Freedom:
      throw InvalidArgument("Ipopt: Not_Enough_Degrees_Of_Freedom (more equality constraints than free variables)" +
                            captured());
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

}  // namespace saltus::timefreezing::detail
