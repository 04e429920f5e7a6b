// Definitions of schedule_extraction.hpp.
#pragma once

#include <saltus/timefreezing/refinement/schedule_extraction.hpp>

#include <algorithm>
#include <memory>

namespace saltus::timefreezing {

namespace detail {

template <int NC>
struct ExtractionPiece {
  Mode<NC> mode;
  double t_begin = 0.0, t_end = 0.0;
  int first_segment = 0, last_segment = 0;
  bool impact_at_start = false;
};

template <Scene S>
double largest_gap(const S& scene, const Segment<S>& segment, int contact) {
  double worst = -std::numeric_limits<double>::infinity();
  for (int k = 0; k <= 20; ++k) {
    const double t = segment.t_begin + (segment.t_end - segment.t_begin) * k / 20.0;
    const VecT<double, 2 * S::nq> x = segment.x.value(std::clamp(t, segment.x.lo(), segment.x.hi()));
    worst = std::max(worst, scene.template gap<double>(contact, VecT<double, S::nq>(x.template head<S::nq>())));
  }
  return worst;
}

template <Scene S>
void read_micro_flights(const S& scene, const HybridTrajectory<S>& trajectory, double gap,
                        std::vector<ExtractionPiece<S::nc>>& pieces, std::vector<ExtractionNote>& notes) {
  for (std::size_t k = 1; k + 1 < pieces.size(); ++k)
    for (int i = 0; i < S::nc; ++i) {
      if (pieces[k].mode[i].closed() || !pieces[k - 1].mode[i].closed() || !pieces[k + 1].mode[i].closed()) continue;
      if (largest_gap(scene, trajectory.segments[static_cast<std::size_t>(pieces[k].first_segment)], i) > gap) continue;
      pieces[k].mode[i] = pieces[k - 1].mode[i];
      notes.push_back({"micro-flight", pieces[k].t_begin, pieces[k].t_end});
    }
}

template <int NC>
void drop_micro_phases(double min_duration, std::vector<ExtractionPiece<NC>>& pieces, std::vector<ExtractionNote>& notes) {
  for (std::size_t k = 0; k < pieces.size() && pieces.size() > 1;) {
    if (pieces[k].t_end - pieces[k].t_begin >= min_duration) {
      ++k;
      continue;
    }
    notes.push_back({"micro-phase", pieces[k].t_begin, pieces[k].t_end});
    const double middle = 0.5 * (pieces[k].t_begin + pieces[k].t_end);
    if (k > 0) {
      pieces[k - 1].t_end = k + 1 < pieces.size() ? middle : pieces[k].t_end;
      pieces[k - 1].last_segment = pieces[k].last_segment;
    }
    if (k + 1 < pieces.size()) {
      pieces[k + 1].t_begin = k > 0 ? middle : pieces[k].t_begin;
      pieces[k + 1].impact_at_start = pieces[k + 1].impact_at_start || pieces[k].impact_at_start;
      if (k == 0) pieces[k + 1].first_segment = pieces[k].first_segment;
    }
    pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(k));
  }
}

template <Scene S>
void merge_equal_modes(const S& scene, std::vector<ExtractionPiece<S::nc>>& pieces, std::vector<ExtractionNote>& notes) {
  for (std::size_t k = 1; k < pieces.size();) {
    const ScheduleEvent change = guards_between(scene, pieces[k - 1].mode, pieces[k].mode);
    if (!change.guards.empty()) {
      ++k;
      continue;
    }
    notes.push_back({"same mode", pieces[k - 1].t_end, pieces[k].t_begin});
    pieces[k - 1].t_end = pieces[k].t_end;
    pieces[k - 1].last_segment = pieces[k].last_segment;
    pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(k));
  }
}

/// Rule 4: the guards of the mode change; at an impact the impulse decides the closed contacts'
/// sub-modes and throws contacts off, so their stop, slip-onset and release guards go.
template <Scene S>
ScheduleEvent event_between(const S& scene, const ExtractionPiece<S::nc>& before, const ExtractionPiece<S::nc>& after) {
  ScheduleEvent e = guards_between(scene, before.mode, after.mode);
  if (!e.impact()) return e;
  std::vector<Guard> kept;
  for (const Guard& g : e.guards)
    if (g.kind == GuardKind::Touchdown) kept.push_back(g);
  e.guards = kept;
  return e;
}

}  // namespace detail

template <Scene S>
ExtractedSchedule<S> extract_schedule(const S& scene, const HybridTrajectory<S>& trajectory,
                                      const ScheduleExtractionOptions& options) {
  options.validate();
  SALTUS_REQUIRE(!trajectory.segments.empty(), "schedule extraction: the trajectory has no segment");
  ExtractedSchedule<S> out;
  std::vector<detail::ExtractionPiece<S::nc>> pieces;
  for (std::size_t k = 0; k < trajectory.segments.size(); ++k) {
    const Segment<S>& s = trajectory.segments[k];
    SALTUS_REQUIRE(!s.x.empty(), "schedule extraction: segment ", k, " has no dense output");
    detail::ExtractionPiece<S::nc> piece;
    for (int i = 0; i < S::nc; ++i) piece.mode[i] = normalised_contact_state(scene, i, s.mode[i]);
    piece.t_begin = s.t_begin;
    piece.t_end = s.t_end;
    piece.first_segment = piece.last_segment = static_cast<int>(k);
    piece.impact_at_start = k > 0 && k - 1 < trajectory.events.size() && trajectory.events[k - 1].impact();
    pieces.push_back(piece);
  }
  detail::read_micro_flights(scene, trajectory, options.micro_flight_gap, pieces, out.notes);
  detail::drop_micro_phases(options.min_phase_duration, pieces, out.notes);
  detail::merge_equal_modes(scene, pieces, out.notes);
  ModeSchedule<S::nc> schedule;
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    schedule.phases.push_back(pieces[k].mode);
    if (k == 0) continue;
    schedule.events.push_back(detail::event_between(scene, pieces[k - 1], pieces[k]));
    out.guess.event_times.push_back(pieces[k].t_begin);
  }
  out.guess.schedule = validated(scene, schedule);
  const auto shared = std::make_shared<const HybridTrajectory<S>>(trajectory);
  std::vector<std::pair<int, int>> ranges;
  for (const auto& p : pieces) ranges.emplace_back(p.first_segment, p.last_segment);
  out.guess.state = [shared, ranges](int phase, double t) {
    const auto [first, last] = ranges[static_cast<std::size_t>(phase)];
    int s = first;
    while (s < last && t > shared->segments[static_cast<std::size_t>(s)].t_end) ++s;
    const Segment<S>& seg = shared->segments[static_cast<std::size_t>(s)];
    return shared->state(s, std::clamp(t, seg.t_begin, seg.t_end));
  };
  out.guess.input = [shared](double t) {
    const int s = shared->segment_at(t);
    const Segment<S>& seg = shared->segments[static_cast<std::size_t>(s)];
    return shared->input_at(s, std::clamp(t, seg.t_begin, seg.t_end));
  };
  return out;
}

}  // namespace saltus::timefreezing
