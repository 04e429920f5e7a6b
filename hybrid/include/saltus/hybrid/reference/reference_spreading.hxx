// Definitions of reference_spreading.hpp (see there for the construction).
#pragma once

#include <saltus/hybrid/reference/reference_spreading.hpp>

namespace saltus {

template <Scene S>
ExtendedReference<S>::ExtendedReference(const S& scene, const HybridTrajectory<S>& reference, ExtensionOptions options)
    : reference_(reference), options_(options) {
  SALTUS_REQUIRE(
      options.before >= 0 && options.after >= 0 && std::isfinite(options.before) && std::isfinite(options.after), "extension lengths must be finite and >= 0, got before ", options.before, ", after ",
      options.after);
  SALTUS_REQUIRE(reference.segment_count() > 0, "the reference has no segments");
  SALTUS_REQUIRE(static_cast<bool>(reference.input), "the reference has no input law");
  options_.integrator.kind = IntegratorKind::DormandPrince;
  DormandPrinceIntegrator<S> integrator(options_.integrator);
  extensions_.resize(reference.segment_count());
  for (int i = 0; i < reference.segment_count(); ++i) {
    const Segment<S>& seg = reference.segments[i];
    Extension& ext = extensions_[i];
    ext.reached_after = seg.t_end;
    ext.reached_before = seg.t_begin;
    ModeSystem<S> sys(scene, extension_law(i));
    sys.set_mode(seg.mode);
    extend(integrator, sys, seg.t_end, reference.state(i, seg.t_end), seg.t_end + options.after, ext.after,
           ext.reached_after);
    extend(integrator, sys, seg.t_begin, reference.state(i, seg.t_begin), seg.t_begin - options.before, ext.before,
           ext.reached_before);
  }
}

template <Scene S>
auto ExtendedReference<S>::state(int i, double t) const -> State {
  const Extension& ext = extension(i);
  const Segment<S>& seg = reference_.segments[i];
  const double slack = 1e-12 * std::max(1.0, std::abs(t));
  SALTUS_REQUIRE(t >= ext.reached_before - slack && t <= ext.reached_after + slack, "t = ", t,
                " is outside the extended segment ", i, " [", ext.reached_before, ", ", ext.reached_after, "]");
  if (t > seg.t_end && !ext.after.empty()) return ext.after.value(t);
  if (t < seg.t_begin && !ext.before.empty()) return ext.before.value(t);
  return reference_.state(i, std::clamp(t, seg.t_begin, seg.t_end));
}

template <Scene S>
auto ExtendedReference<S>::input(int i, double t) const -> Input {
  const Segment<S>& seg = reference_.segments[i];
  if (options_.input == InputExtension::Hold) {
    const double tc = std::clamp(t, seg.t_begin, seg.t_end);
    return reference_.input(tc, reference_.state(i, tc), seg.mode);
  }
  return reference_.input(t, state(i, t), seg.mode);
}

template <Scene S>
auto ExtendedReference<S>::extension(int i) const -> const Extension& {
  SALTUS_REQUIRE(i >= 0 && i < segment_count(), "segment index ", i, " out of range [0, ",
                segment_count(), ")");
  return extensions_[i];
}

template <Scene S>
auto ExtendedReference<S>::extension_law(int i) const -> InputLaw<S> {
  if (options_.input == InputExtension::Evaluate) return reference_.input;
  const Segment<S>& seg = reference_.segments[i];
  const Input u_begin = reference_.input(seg.t_begin, reference_.state(i, seg.t_begin), seg.mode);
  const Input u_end = reference_.input(seg.t_end, reference_.state(i, seg.t_end), seg.mode);
  const double t_begin = seg.t_begin, t_end = seg.t_end;
  const InputLaw<S> law = reference_.input;
  return [=](double t, const State& x, const Mode<nc>& mode) -> Input {
    if (t >= t_end) return u_end;
    if (t <= t_begin) return u_begin;
    return law(t, x, mode);
  };
}

template <Scene S>
void ExtendedReference<S>::extend(DormandPrinceIntegrator<S>& integrator, ModeSystem<S>& sys, double t0, State x,
                                  double t1, DenseOutput<nx>& out, double& reached) {
  reached = t0;
  if (t1 == t0) return;
  try {
    const auto end = integrator.integrate(sys, t0, x, t1, 0.0, &out, /*detect_events=*/false);
    reached = end.t;
  } catch (const NumericalFailure&) {
    // The mode's flow ends here (documented above); keep what was integrated.
    reached = out.empty() ? t0 : out.end();
  }
}

}  // namespace saltus
