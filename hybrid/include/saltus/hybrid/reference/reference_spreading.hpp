// Reference spreading: every segment of a reference trajectory extended past its end and before
// its start by integrating its own mode's flow (events disabled) under its own input law, so that
// a perturbed motion whose events come earlier or later than the reference's is always compared
// with the reference segment that has seen the same number of jumps (DESIGN.md, "Reference
// spreading"). Past a touchdown the extension of the pre-impact segment keeps falling below the
// ground; before a release the post-release segment's extension is the free flight run backwards.
//
// Input extension. The extension evaluates the segment's input law with the segment's own mode,
// u = law(t, x, mode), in one of two ways:
//  - Evaluate: at the extended time and state, u(t) = law(t, x_ext(t), mode): an open-loop law
//    is continued as written (a ramp keeps ramping), a feedback law acts on the extended state;
//  - Hold: the law evaluated at the clamped time t_c = clamp(t, t_begin, t_end) and the
//    reference state there, u(t) = law(t_c, x(t_c), mode): the segment's boundary input is held
//    (zero-order hold), e.g. for inputs that are only meaningful inside their segment.
// Lengths `before` and `after` are options (seconds). An extension stops early, without error, if
// the mode's flow cannot be integrated further (e.g. a spatial slip whose velocity reverses, where
// the friction direction is undefined); reached_before/reached_after say how far it went.
#pragma once

#include <saltus/hybrid/simulation/integrator_dopri.hpp>
#include <saltus/hybrid/vocabulary/trajectory.hpp>

#include <vector>

namespace saltus {

enum class InputExtension { Hold, Evaluate };

struct ExtensionOptions {
  double before = 0.05;  ///< s, extension before each segment's start
  double after = 0.05;   ///< s, extension past each segment's end
  InputExtension input = InputExtension::Evaluate;
  /// Integration of the extensions (Dormand-Prince; kind is ignored).
  IntegratorOptions integrator = [] {
    IntegratorOptions o;
    o.relative_tolerance = 1e-12;
    o.absolute_tolerance = 1e-13;
    // An extension that blows up (a damped closed loop run backwards grows like exp(d t)) stops
    // at its step limit without error; 10^5 steps fail it in ~0.1 s instead of the 10^7 default's
    // tens of seconds, and are far more than a regular extension needs (~10^3 at these tolerances).
    o.max_steps = 100'000;
    return o;
  }();
};

template <Scene S>
class ExtendedReference {
 public:
  static constexpr int nq = S::nq, nx = 2 * S::nq, nu = S::nu, nc = S::nc;
  using State = VecT<double, nx>;
  using Input = VecT<double, nu>;

  /// Extends every segment of `reference` (which must keep its input law). The reference must
  /// outlive this object (the scene only the constructor). Throws InvalidArgument on negative lengths or a
  /// reference without segments or input law.
  ExtendedReference(const S& scene, const HybridTrajectory<S>& reference, ExtensionOptions options = {});

  int segment_count() const { return reference_.segment_count(); }
  const HybridTrajectory<S>& reference() const { return reference_; }
  const ExtensionOptions& options() const { return options_; }

  /// The extended interval of segment i (as far as the extension got).
  double t_begin(int i) const { return extension(i).reached_before; }
  double t_end(int i) const { return extension(i).reached_after; }
  double reached_before(int i) const { return extension(i).reached_before; }
  double reached_after(int i) const { return extension(i).reached_after; }

  /// x of segment i at any t of its extended interval: the reference inside the segment, its own
  /// mode's flow outside.
  State state(int i, double t) const;

  /// u of segment i at t, by the input extension of the options.
  Input input(int i, double t) const;

 private:
  struct Extension {
    DenseOutput<nx> before, after;
    double reached_before = 0.0, reached_after = 0.0;
  };

  const Extension& extension(int i) const;

  // The input law the extension of segment i integrates with.
  InputLaw<S> extension_law(int i) const;

  static void extend(DormandPrinceIntegrator<S>& integrator, ModeSystem<S>& sys, double t0, State x, double t1,
                     DenseOutput<nx>& out, double& reached);

  const HybridTrajectory<S>& reference_;
  ExtensionOptions options_;
  std::vector<Extension> extensions_;
};

}  // namespace saltus
