// The definitions of recover_reference and of the discrete solution's control samples
// (recover_reference.hpp, where the rules are stated).
#pragma once

#include <saltus/timefreezing/recovery/recover_reference.hpp>
#include <saltus/timefreezing/recovery/recover_trajectory.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace saltus::timefreezing {

namespace detail {

template <int ny, int nsw, int nu>
void check_stage_points(const std::vector<FesdPoint<ny, nsw, nu>>& points, int stages, const char* who) {
  SALTUS_REQUIRE(stages >= 1 && points.size() >= 1 + static_cast<std::size_t>(stages) &&
                     (points.size() - 1) % static_cast<std::size_t>(stages) == 0,
                 who, ": expected the initial point and n_s points per element, got ", points.size(),
                 " points for n_s = ", stages);
  SALTUS_REQUIRE(stages <= 3, who, ": n_s must be 1, 2 or 3 (Radau IIA), got ", stages);
  // The points record their stage: a wrong n_s would pair stages of different elements.
  for (std::size_t k = 1; k < points.size(); ++k)
    SALTUS_REQUIRE(points[k].stage == static_cast<int>((k - 1) % static_cast<std::size_t>(stages)), who,
                   ": point ", k, " is stage ", points[k].stage, " of its element, but n_s = ", stages,
                   " makes it stage ", (k - 1) % static_cast<std::size_t>(stages));
}

template <Scene S, int ny, int nsw, int nu>
ImportedReference<S> control_samples(const std::vector<FesdPoint<ny, nsw, nu>>& points, int stages) {
  check_stage_points(points, stages, "recover_trajectory");
  constexpr int nx = 2 * S::nq;
  const auto n = static_cast<std::size_t>(stages);
  ImportedReference<S> samples;
  auto add = [&](double t, const VecT<double, nu>& u) {
    samples.t.push_back(t);
    samples.u.push_back(u);
  };
  add(points[0].y[nx], points[0].u);
  const std::size_t elements = (points.size() - 1) / n;
  for (std::size_t e = 0; e < elements; ++e) {
    const auto& end = points[(e + 1) * n];
    add(end.y[nx], end.u);
    if (e + 1 < elements && points[1 + (e + 1) * n].interval != end.interval) add(end.y[nx], points[1 + (e + 1) * n].u);
  }
  return samples;
}

/// One sampling of a recovered trajectory (recover_reference): walks the elements once, writing
/// the samples' times, inputs and segments and marking the samples that are an impact's x- or x+;
/// then reads every state off the trajectory.
template <Scene S, int ny, int nsw, int nu>
class ReferenceSampling {
 public:
  using Point = FesdPoint<ny, nsw, nu>;
  using Input = typename ImportedReference<S>::Input;
  static constexpr int nx = 2 * S::nq;

  ReferenceSampling(const HybridTrajectory<S>& trajectory, const std::vector<Point>& points, int stages,
                    double frozen_tolerance)
      : traj_(trajectory), points_(points), stages_(stages), frozen_tolerance_(frozen_tolerance),
        elements_(static_cast<int>((points.size() - 1) / static_cast<std::size_t>(stages))) {
    for (std::size_t e = 0; e < traj_.events.size(); ++e)
      if (traj_.events[e].impact()) impacts_.push_back(e);
  }

  ImportedReference<S> run() {
    add(clock(points_[0]), points_[0].u, Role::Flow);
    for (int e = 0; e < elements_;) {
      if (element_frozen(points_, stages_, e, frozen_tolerance_)) {
        int f = e;
        while (f + 1 < elements_ && element_frozen(points_, stages_, f + 1, frozen_tolerance_)) ++f;
        const double next = f + 1 < elements_ ? clock(end_of(f + 1)) : std::numeric_limits<double>::infinity();
        impact_at(end_of(f).u, next);  // a run of frozen elements: the impact it resolved
        e = f + 1;
      } else {
        impact_at(end_of(e).u, clock(end_of(e)));  // an impact absorbed into this element
        add(clock(end_of(e)), end_of(e).u, Role::Flow);
        ++e;
      }
      if (e < elements_ && stage_of(e, 0).interval != end_of(e - 1).interval)
        add(clock(end_of(e - 1)), stage_of(e, 0).u, Role::Flow);  // the next interval's input
    }
    SALTUS_REQUIRE(next_impact_ == impacts_.size(), "recover_reference: the trajectory's impact at t = ",
                   next_impact_ < impacts_.size() ? traj_.events[impacts_[next_impact_]].t : 0.0,
                   " lies at no element boundary of the points (a trajectory of other points?)");
    read_states();
    return std::move(ref_);
  }

 private:
  enum class Role { Flow, XMinus, XPlus };

  const Point& stage_of(int e, int r) const { return points_[static_cast<std::size_t>(1 + e * stages_ + r)]; }
  const Point& end_of(int e) const { return stage_of(e, stages_ - 1); }
  static double clock(const Point& p) { return p.y[nx]; }

  void add(double t, const Input& u, Role role) {
    ref_.t.push_back(t);
    ref_.u.push_back(u);
    ref_.segment.push_back(segment_);
    roles_.push_back(role);
  }

  /// If the trajectory's next impact is at the last sample's time: the samples at that time
  /// become x- (the last) and the segment ends; x+ is a sample of its own at x_plus_time when that
  /// comes before `next` (the next sample's time), otherwise the next sample is x+.
  void impact_at(const Input& u, double next) {
    if (next_impact_ >= impacts_.size()) return;
    const std::size_t e = impacts_[next_impact_];
    const double t = traj_.events[e].t;
    if (std::abs(t - ref_.t.back()) > 1e-12 * (1.0 + std::abs(t))) return;
    ++next_impact_;
    roles_.back() = Role::XMinus;
    ref_.event_times.push_back(ref_.t.back());
    ++segment_;
    const double t_plus = x_plus_time(traj_, e);
    if (t_plus < next) add(t_plus, u, Role::XPlus);
  }

  /// The state of every sample: an impact's x- and x+ from its event, the others from the
  /// trajectory's segment between the same impacts that contains the sample's time.
  void read_states() {
    ref_.x.resize(ref_.t.size());
    for (std::size_t k = 0; k < ref_.t.size(); ++k) {
      const auto s = static_cast<std::size_t>(ref_.segment[k]);
      if (roles_[k] == Role::XMinus) ref_.x[k] = traj_.events[impacts_[s]].x_minus;
      else if (roles_[k] == Role::XPlus) ref_.x[k] = traj_.events[impacts_[s - 1]].x_plus;
      else ref_.x[k] = state_between_impacts(s, ref_.t[k]);
    }
  }

  typename ImportedReference<S>::State state_between_impacts(std::size_t s, double t) const {
    const int first = s == 0 ? 0 : static_cast<int>(impacts_[s - 1]) + 1;
    const int last = s < impacts_.size() ? static_cast<int>(impacts_[s]) : traj_.segment_count() - 1;
    int i = first;
    while (i < last && traj_.segments[static_cast<std::size_t>(i + 1)].t_begin <= t) ++i;
    const auto& seg = traj_.segments[static_cast<std::size_t>(i)];
    return traj_.state(i, std::clamp(t, seg.t_begin, seg.t_end));
  }

  const HybridTrajectory<S>& traj_;
  const std::vector<Point>& points_;
  int stages_;
  double frozen_tolerance_;
  int elements_;
  std::vector<std::size_t> impacts_;  ///< the trajectory's impact events, by index
  std::size_t next_impact_ = 0;
  int segment_ = 0;
  ImportedReference<S> ref_;
  std::vector<Role> roles_;
};

}  // namespace detail

template <Scene S, int ny, int nsw, int nu>
ImportedReference<S> recover_reference(const HybridTrajectory<S>& trajectory,
                                       const std::vector<FesdPoint<ny, nsw, nu>>& points, int stages,
                                       double frozen_tolerance) {
  detail::check_stage_points(points, stages, "recover_reference");
  SALTUS_REQUIRE(std::isfinite(frozen_tolerance) && frozen_tolerance > 0.0,
                 "recover_reference: frozen_tolerance must be finite and > 0, got ", frozen_tolerance);
  return detail::ReferenceSampling<S, ny, nsw, nu>(trajectory, points, stages, frozen_tolerance).run();
}

}  // namespace saltus::timefreezing
