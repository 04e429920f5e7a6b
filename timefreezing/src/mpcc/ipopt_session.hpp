// Private: one Ipopt application per solve_mpcc or check_derivatives call, configured from the
// options, with Ipopt's messages captured for our exceptions. Only the sources of
// saltus_timefreezing include this header (it includes Ipopt's).
#pragma once

#include <IpIpoptApplication.hpp>
#include <IpJournalist.hpp>
#include <cstdarg>
#include <cstddef>
#include <saltus/timefreezing/mpcc/solver_options.hpp>
#include <string>

namespace saltus::timefreezing::detail {

/// Ipopt's ApplicationReturnStatus by name, e.g. "Solve_Succeeded".
std::string status_name(Ipopt::ApplicationReturnStatus status);

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
  void PrintfImpl(Ipopt::EJournalCategory, Ipopt::EJournalLevel, const char* pformat, va_list ap) override;
  void FlushBufferImpl() override {}

 private:
  void append(const char* str);
  std::string text_;
  std::size_t max_chars_;
};

/// An IpoptApplication that prints nothing unless print_level > 0, reads no ipopt.opt, lets the
/// problem's own exceptions through, and captures Ipopt's error messages (for our exceptions).
/// Options are set before initialize(); between solves (max_iter, warm_start_init_point) too.
struct IpoptSession {
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app;
  Ipopt::SmartPtr<CaptureJournal> capture;

  explicit IpoptSession(int print_level);

  /// "; Ipopt said: ..." with the captured messages, "" when there are none.
  std::string captured() const;
  /// Each throws InvalidArgument (naming the option, its value and Ipopt's message) when Ipopt
  /// rejects the option or its value.
  void set_string(const std::string& name, const std::string& value);
  void set_integer(const std::string& name, int value);
  void set_number(const std::string& name, double value);
  void set(const IpoptOption& option);
  /// Ipopt::IpoptApplication::Initialize from an empty stream (no ./ipopt.opt); throws
  /// InvalidArgument when Ipopt refuses.
  void initialize();
  /// Iterations of the last solve (0 when Ipopt kept no statistics).
  int iterations();
  /// Ipopt statuses that say the problem or the setup is wrong, or Ipopt broke, are thrown, not
  /// reported as a failed step (a retry could not help): Invalid_Option,
  /// Not_Enough_Degrees_Of_Freedom and Invalid_Problem_Definition as InvalidArgument; the internal
  /// errors as NumericalFailure. Other statuses return.
  void throw_on_setup_error(Ipopt::ApplicationReturnStatus status);
};

}  // namespace saltus::timefreezing::detail
