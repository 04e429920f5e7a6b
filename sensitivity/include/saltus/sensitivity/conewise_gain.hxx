// Definitions of conewise_gain.hpp (see there for the derivation).
#pragma once

#include <saltus/hybrid/simulation/mode_system.hpp>
#include <saltus/hybrid/simulation/transition.hpp>
#include <saltus/sensitivity/conewise_gain.hpp>
#include <saltus/sensitivity/detail/dense.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>

namespace saltus {

template <Scene S>
bool ConewisePiece<S>::contains(const Vec<nx>& z, const Vec<nu>& v, double tolerance) const {
  if (cone_z.rows() == 0) return true;
  double scale = z.norm();
  if constexpr (nu > 0) scale = std::hypot(scale, v.norm());
  for (int r = 0; r < cone_z.rows(); ++r) {
    double value = cone_z.row(r).dot(z), norm = cone_z.row(r).norm();
    if constexpr (nu > 0) {
      value += cone_v.row(r).dot(v);
      norm = std::hypot(norm, cone_v.row(r).norm());
    }
    if (norm > 0 && value < -tolerance * scale * norm) return false;
  }
  return true;
}

template <Scene S>
struct ConewiseJumpGain<S>::Node {
  State x = State::Zero();  ///< intermediate state at t*
  Mode<nc> mode{};          ///< intermediate mode
  Mat<nx, nx> Zz = Mat<nx, nx>::Identity();  ///< z_N = Zz z- + Zv v
  Mat<nx, nu> Zv = Mat<nx, nu>::Zero();
  std::vector<Guard> fired, never_crossed;
  /// The event's guards whose contacts are open here and moving away (rate > 0): fired ones that
  /// a later impulse released, and ones not fired yet that an impulse sent away. Held back
  /// (`deferred`) in the next micro-event: their gaps are of order eps and positive.
  std::vector<Guard> away;
  std::vector<std::vector<Guard>> order;  ///< the micro-events so far, each a group of guards
  /// The deepest direction of the path's cone (nx + nu, unit) and its margin (conewise_gain.hpp).
  Eigen::Matrix<double, nx + nu, 1> interior = Eigen::Matrix<double, nx + nu, 1>::Unit(0);
  double margin = std::numeric_limits<double>::infinity();
  /// The crossing guards, grouped where they coincide (the same first-order shift: they fire
  /// together in every nearby motion, "Coincident guards" in jump_gain.hpp).
  std::vector<std::vector<Guard>> crossing;
  /// Rows of the first-order crossing-time shifts of the groups: dt = dt_z z- + dt_v v.
  Eigen::Matrix<double, Eigen::Dynamic, nx> dt_z;
  Eigen::Matrix<double, Eigen::Dynamic, nu> dt_v;
  /// The cone of the path to this node.
  Eigen::Matrix<double, Eigen::Dynamic, nx> cone_z;
  Eigen::Matrix<double, Eigen::Dynamic, nu> cone_v;
  std::vector<Event<S>> steps;
  double seconds = 0.0;
  std::vector<std::unique_ptr<Node>> children;  ///< one per crossing group, built lazily
  /// Per crossing group: its cone was found to have no interior (the order cannot happen).
  std::vector<char> empty_cone;
  std::unique_ptr<Piece> piece;                 ///< a leaf's piece
};

namespace detail {
inline std::string describe_guard(const char* contact_name, const Guard& g) {
  return concat(to_string(g.kind), " of '", contact_name, "'");
}
}  // namespace detail

template <Scene S>
std::string ConewiseJumpGain<S>::describe_order(const std::vector<Guard>& fired) const {
  std::string s = "[";
  for (std::size_t k = 0; k < fired.size(); ++k) {
    if (k) s += ", ";
    s += detail::describe_guard(scene_.contact(fired[k].contact).name.c_str(), fired[k]);
  }
  return s + "]";
}

template <Scene S>
ConewiseJumpGain<S>::ConewiseJumpGain(const S& scene, const Event<S>& event, const InputLaw<S>& law,
                                      ConewiseGainOptions options)
    : scene_(scene), event_(event), law_(law), options_(options) {
  SALTUS_REQUIRE(static_cast<bool>(law), "conewise gain: the input law is empty");
  SALTUS_REQUIRE(!event.transitions.empty() && !event.transitions.front().guards.empty(),
                 "conewise gain: the event at t = ", event.t, " has no guarded first transition (an initial impact "
                 "has a fixed time and a linear gain: JumpGainSolver)");
  SALTUS_REQUIRE(options.outcome_tolerance >= 0, "ConewiseGainOptions: outcome_tolerance must be >= 0");
  SALTUS_REQUIRE(options.max_micro_events >= 1, "ConewiseGainOptions: max_micro_events must be >= 1");
  SALTUS_REQUIRE(options.empty_cone_tolerance > 0 && options.empty_cone_tolerance < 1,
                 "ConewiseGainOptions: empty_cone_tolerance must be in (0, 1) (a distance between unit rows' hull and "
                 "the origin, found to round-off: 0 would call no cone empty), got ", options.empty_cone_tolerance);
  guards_ = event.transitions.front().guards;
  resolver_ = std::make_unique<TransitionResolver<S>>(scene, options.simulation);
  gains_ = std::make_unique<JumpGainSolver<S>>(scene, options.gains);
  root_ = std::make_unique<Node>();
  root_->x = event.transitions.front().x_before;
  root_->mode = event.transitions.front().mode_before;
  SALTUS_REQUIRE(!event.input_jump, "conewise gain: the event at t = ", event.t,
                 " was fired by a jump of the input (Event::input_jump): its time is fixed and its gain linear "
                 "(JumpGainSolver)");
  const auto start = std::chrono::steady_clock::now();
  classify(*root_);
  // Every guard of the event crosses at x- (it fired): none may be dropped at the root.
  for (const UnrealisableOrder& u : unrealisable_) {
    const Guard& g = u.next.front();
    const std::string name = detail::describe_guard(scene.contact(g.contact).name.c_str(), g);
    SALTUS_REQUIRE(u.reason != UnrealisableOrder::Reason::NoLongerAGuard, "conewise gain: the ", name,
                   " fired at t = ", event.t, " is not a guard of the mode before the event");
    throw GrazingEvent(detail::concat("conewise gain: the ", name, " fired at t = ", event.t,
                                      " but does not cross there (rate ", u.gamma_dot, " >= 0 along the mode before)"),
                       event.t, g, u.gamma_dot, 0.0);
  }
  root_->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

template <Scene S>
ConewiseJumpGain<S>::~ConewiseJumpGain() = default;
template <Scene S>
ConewiseJumpGain<S>::ConewiseJumpGain(ConewiseJumpGain&&) noexcept = default;

template <Scene S>
void ConewiseJumpGain<S>::classify(Node& node) {
  // Every guard of the event is classified afresh at each node: one that an impulse sent away
  // may be approached again after a later one, and one that fired, closed its contact and was
  // released by a later impulse is a guard again (a re-touchdown: conewise_gain.hpp).
  const double t = event_.t;
  const GuardList<nc> active = active_guards(scene_, node.mode);
  std::vector<Eigen::Matrix<double, 1, nx>> rows_z;
  std::vector<Eigen::Matrix<double, 1, nu>> rows_v;
  node.never_crossed.clear();
  node.away.clear();
  for (const Guard& g : guards_) {
    const bool fired_before = std::find(node.fired.begin(), node.fired.end(), g) != node.fired.end();
    const bool is_active = std::find(active.begin(), active.end(), g) != active.end();
    if (fired_before && !is_active) continue;  // its contact closed when it fired, and is still closed
    if (!is_active) {
      // The contact's mode changed in a micro-event so that this guard no longer exists.
      node.never_crossed.push_back(g);
      unrealisable_.push_back({node.fired, {g}, UnrealisableOrder::Reason::NoLongerAGuard,
                               std::numeric_limits<double>::quiet_NaN()});
      continue;
    }
    const GuardCrossing<S>& c = gains_->crossing(law_, t, node.x, node.mode, g);
    const double threshold = options_.gains.grazing_threshold * c.rate_scale;
    if (fired_before && std::isfinite(c.gamma_dot) && std::abs(c.gamma_dot) <= threshold) {
      // Fired, then opened by the mode selection with zero normal velocity (a lift-off at the
      // acceleration level after a later impulse): it leaves the surface at second order, so it
      // is held back like a contact moving away and cannot come back within the cascade.
      node.away.push_back(g);
      continue;
    }
    if (!std::isfinite(c.gamma_dot) || std::abs(c.gamma_dot) <= threshold) {
      throw GrazingEvent(
          detail::concat("conewise gain: after the micro-events ", describe_order(node.fired), " of the event at t = ", t,
                         ", the ", detail::describe_guard(scene_.contact(g.contact).name.c_str(), g),
                         " is near-grazing: |gamma_dot| = ", std::abs(c.gamma_dot), " <= ",
                         options_.gains.grazing_threshold, " * rate scale ", c.rate_scale,
                         "; the order of its crossing is not differentiable there"),
          t, g, c.gamma_dot, c.rate_scale);
    }
    if (c.gamma_dot > 0) {  // sent away (or released): it cannot be the next micro-event
      node.away.push_back(g);
      if (!fired_before) {
        node.never_crossed.push_back(g);
        unrealisable_.push_back({node.fired, {g}, UnrealisableOrder::Reason::SentAway, c.gamma_dot});
      }
      continue;
    }
    const Eigen::Matrix<double, 1, nx> rz = -(c.dgamma_x * node.Zz) / c.gamma_dot;
    Eigen::Matrix<double, 1, nu> rv = Eigen::Matrix<double, 1, nu>::Zero();
    if constexpr (nu > 0) rv = -(c.dgamma_x * node.Zv + c.dgamma_u) / c.gamma_dot;
    bool grouped = false;
    for (std::size_t k = 0; k < node.crossing.size() && !grouped; ++k) {
      const double scale = std::max({std::hypot(rz.norm(), rv.norm()), std::hypot(rows_z[k].norm(), rows_v[k].norm()), 1e-300});
      const double difference = std::hypot((rz - rows_z[k]).norm(), (rv - rows_v[k]).norm());
      if (difference <= options_.gains.coincidence_tolerance * scale) {
        node.crossing[k].push_back(g);
        grouped = true;
      }
    }
    if (grouped) continue;
    node.crossing.push_back({g});
    rows_z.push_back(rz);
    rows_v.push_back(rv);
  }
  const int k = static_cast<int>(node.crossing.size());
  node.dt_z.resize(k, nx);
  node.dt_v.resize(k, nu);
  for (int i = 0; i < k; ++i) {
    node.dt_z.row(i) = rows_z[i];
    if constexpr (nu > 0) node.dt_v.row(i) = rows_v[i];  // (no rows of a 0-column matrix: UB in Eigen's Block)
  }
  node.children.resize(k);
  node.empty_cone.assign(k, 0);
}

template <Scene S>
auto ConewiseJumpGain<S>::child(Node& node, int k) -> Node* {
  if (node.children[k]) return node.children[k].get();
  if (node.empty_cone[k]) return nullptr;
  const auto start = std::chrono::steady_clock::now();
  const double t = event_.t;
  const std::vector<Guard>& group = node.crossing[k];
  // The cone: the path's rows and dt_i - dt_k >= 0 for every other crossing group i.
  const int others = static_cast<int>(node.crossing.size()) - 1;
  const int r0 = static_cast<int>(node.cone_z.rows());
  Eigen::Matrix<double, Eigen::Dynamic, nx> cone_z(r0 + others, nx);
  Eigen::Matrix<double, Eigen::Dynamic, nu> cone_v(r0 + others, nu);
  cone_z.topRows(r0) = node.cone_z;
  if constexpr (nu > 0) cone_v.topRows(r0) = node.cone_v;
  for (int i = 0, r = r0; i <= others; ++i) {
    if (i == k) continue;
    cone_z.row(r) = node.dt_z.row(i) - node.dt_z.row(k);
    if constexpr (nu > 0) cone_v.row(r) = node.dt_v.row(i) - node.dt_v.row(k);
    ++r;
  }
  // A cone without interior holds no open set of perturbations: the order happens on a set of
  // measure zero only (three corners of a flat face down force the fourth down with them, so
  // the diagonal corner of the first one is never the second to land). Reported, not built.
  Eigen::Matrix<double, nx + nu, 1> interior = node.interior;
  double margin = node.margin;
  if (cone_z.rows() > r0) {
    Eigen::MatrixXd rows(cone_z.rows(), nx + nu);
    rows.leftCols(nx) = cone_z;
    if constexpr (nu > 0) rows.rightCols(nu) = cone_v;
    for (int r = 0; r < rows.rows(); ++r) {
      const double norm = rows.row(r).norm();
      if (norm > 0) rows.row(r) /= norm;
    }
    Eigen::VectorXd nearest;
    const double distance = detail::nearest_hull_point(rows, nearest);
    // The margin certified at the direction found (Wolfe's point is the nearest only to its
    // stopping tolerance): the smallest normalised row there.
    margin = distance > 0 ? (rows * nearest).minCoeff() / distance : 0.0;
    if (!(margin > options_.empty_cone_tolerance)) {
      node.empty_cone[k] = 1;
      unrealisable_.push_back({node.fired, group, UnrealisableOrder::Reason::EmptyCone, 0.0});
      return nullptr;
    }
    interior = nearest / distance;
  }
  // A cascade of re-touchdowns that does not end within the bound: Zeno-like at first order (or
  // a cycle of releases), no finite composition of micro-events describes it.
  if (static_cast<int>(node.order.size()) >= options_.max_micro_events)
    throw NumericalFailure(detail::concat(
        "conewise gain: after ", node.order.size(), " micro-events ", describe_order(node.fired), " of the event at t = ",
        t, " guards still cross (", describe_order(group), " next): more than max_micro_events = ",
        options_.max_micro_events, " (raise the bound; if the guards keep re-firing, the cascade of re-touchdowns "
        "is Zeno-like at first order and no finite composition describes it)"));
  auto c = std::make_unique<Node>();
  c->interior = interior;
  c->margin = margin;
  c->fired = node.fired;
  c->fired.insert(c->fired.end(), group.begin(), group.end());
  c->order = node.order;
  c->order.push_back(group);
  c->cone_z = std::move(cone_z);
  c->cone_v = std::move(cone_v);
  // The guards still to come are held back, and so are those sent away: in the perturbed motion
  // their contacts are at a positive gap of order eps when this micro-event happens.
  std::vector<Guard> deferred = node.away;
  for (int i = 0; i <= others; ++i)
    if (i != k) deferred.insert(deferred.end(), node.crossing[i].begin(), node.crossing[i].end());
  const std::string order = describe_order(c->fired);
  ModeSystem<S> sys(scene_, law_);
  sys.set_mode(node.mode);
  Event<S> step;
  try {
    step = resolver_->resolve(sys, t, node.x, node.mode, group, deferred);
  } catch (const ContactProblemFailure& e) {
    throw ContactProblemFailure(detail::concat("conewise gain, micro-event order ", order, ": ", e.what()));
  } catch (const NumericalFailure& e) {
    throw NumericalFailure(detail::concat("conewise gain, micro-event order ", order, ": ", e.what()));
  }
  try {
    // Composed from node's maps: the step's dt and its coincident guards in terms of (z-, v).
    const JumpGain<S>& sg = gains_->compute(step, law_, node.Zz, node.Zv);
    c->Zz = sg.G_z;
    c->Zv = sg.G_v;
  } catch (const GrazingEvent& e) {
    throw GrazingEvent(detail::concat("conewise gain, micro-event order ", order, ": ", e.what()), e.t(), e.guard(),
                       e.gamma_dot(), e.rate_scale());
  } catch (const SimultaneousActivation& e) {
    throw SimultaneousActivation(detail::concat("conewise gain, micro-event order ", order, ": ", e.what()));
  } catch (const ContactProblemFailure& e) {
    throw ContactProblemFailure(detail::concat("conewise gain, micro-event order ", order, ": ", e.what()));
  }
  c->x = step.x_plus;
  c->mode = step.mode_after;
  c->steps = node.steps;
  c->steps.push_back(std::move(step));
  classify(*c);
  c->seconds = node.seconds + std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (c->crossing.empty()) {  // a leaf: the piece
    auto p = std::make_unique<Piece>();
    p->order = c->order;
    p->never_crossed = c->never_crossed;
    p->G_z = c->Zz;
    p->G_v = c->Zv;
    p->cone_z = c->cone_z;
    p->cone_v = c->cone_v;
    p->interior_direction = c->interior;
    p->interior_margin = c->margin;
    p->x_plus = c->x;
    p->mode_after = c->mode;
    p->post_state_difference = (c->x - event_.x_plus).cwiseAbs().maxCoeff();
    // The same contact modes (a spatial slip's stored direction compared to the outcome
    // tolerance: it is the sliding direction at the slip's start, computed from round-off-level
    // different states) and the same post-event state.
    const double tolerance = options_.outcome_tolerance * std::max(1.0, event_.x_plus.cwiseAbs().maxCoeff());
    bool same_modes = true;
    for (int i = 0; i < nc; ++i) {
      const ContactState &a = c->mode[i], &b = event_.mode_after[i];
      same_modes = same_modes && a.mode == b.mode &&
                   (a.mode != ContactMode::Slip || (a.slip_direction - b.slip_direction).norm() <= options_.outcome_tolerance);
    }
    p->nominal_outcome = same_modes && p->post_state_difference <= tolerance;
    p->steps = c->steps;
    p->build_seconds = c->seconds;
    pieces_.push_back(p.get());
    c->piece = std::move(p);
  }
  node.children[k] = std::move(c);
  return node.children[k].get();
}

template <Scene S>
auto ConewiseJumpGain<S>::piece(const State& z_minus, const Input& v) -> const Piece& {
  SALTUS_REQUIRE(z_minus.allFinite() && v.allFinite(), "conewise gain: the deviation (z-, v) is not finite");
  Node* node = root_.get();
  // Allocation-free (evaluate() runs in predictions and closed-loop jumps): at most one crossing
  // group per guard of a mode, 2 nc + 1.
  constexpr int capacity = 2 * nc + 1;
  std::array<double, capacity> dt{};
  std::array<int, capacity> candidates{};
  while (!node->crossing.empty()) {
    const int k = static_cast<int>(node->crossing.size());
    SALTUS_INVARIANT(k <= capacity, "at most one crossing group per guard");
    for (int i = 0; i < k; ++i) {
      dt[i] = node->dt_z.row(i).dot(z_minus);
      if constexpr (nu > 0) dt[i] += node->dt_v.row(i).dot(v);
      candidates[i] = i;
    }
    // The earliest crossing; ties (a face) to the first listed (a stable insertion sort). A cone
    // without interior can be the argmin only on its (measure-zero) set: the next earliest is
    // taken then.
    for (int i = 1; i < k; ++i)
      for (int j = i; j > 0 && dt[candidates[j]] < dt[candidates[j - 1]]; --j) std::swap(candidates[j], candidates[j - 1]);
    Node* next = nullptr;
    for (int i = 0; i < k && next == nullptr; ++i) next = child(*node, candidates[i]);
    SALTUS_INVARIANT(next != nullptr, "the cones of a node's children cover every direction");
    node = next;
  }
  SALTUS_INVARIANT(node->piece != nullptr, "a node without crossing guards is a leaf with a piece");
  return *node->piece;
}

template <Scene S>
auto ConewiseJumpGain<S>::evaluate(const State& z_minus, const Input& v) -> State {
  const Piece& p = piece(z_minus, v);
  State z = p.G_z * z_minus;
  if constexpr (nu > 0) z += p.G_v * v;
  return z;
}

template <Scene S>
int ConewiseJumpGain<S>::build_all() {
  std::vector<Node*> stack{root_.get()};
  while (!stack.empty()) {
    Node* node = stack.back();
    stack.pop_back();
    for (int k = 0; k < static_cast<int>(node->crossing.size()); ++k)
      if (Node* c = child(*node, k)) stack.push_back(c);
  }
  return static_cast<int>(pieces_.size());
}

template <Scene S>
double ConewiseJumpGain<S>::face_discontinuity(int samples, int* faces, unsigned seed) {
  SALTUS_REQUIRE(samples > 0, "face_discontinuity: samples must be > 0");
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  constexpr int n = nx + nu;
  double worst = 0.0;
  int checked = 0;
  for (int s = 0; s < samples; ++s) {
    Eigen::Matrix<double, n, 1> p;
    for (int k = 0; k < n; ++k) p[k] = normal(rng);
    p.normalize();
    const Piece& a = piece(p.template head<nx>(), p.template tail<nu>());
    for (int r = 0; r < a.cone_z.rows(); ++r) {
      Eigen::Matrix<double, n, 1> row;
      row.template head<nx>() = a.cone_z.row(r).transpose();
      if constexpr (nu > 0) row.template tail<nu>() = a.cone_v.row(r).transpose();
      const double rn = row.norm();
      if (!(rn > 0)) continue;
      // The point of the face's hyperplane nearest to p, kept if it lies on the cone's boundary.
      Eigen::Matrix<double, n, 1> f = p - (row.dot(p) / (rn * rn)) * row;
      const double fn = f.norm();
      if (!(fn > 1e-6) || !a.contains(f.template head<nx>(), f.template tail<nu>(), 1e-12)) continue;
      const Eigen::Matrix<double, n, 1> out = f - 1e-7 * fn / rn * row;
      const Piece& b = piece(out.template head<nx>(), out.template tail<nu>());
      if (&b == &a || b.nominal_outcome != a.nominal_outcome) continue;
      if (!a.nominal_outcome && (a.x_plus - b.x_plus).cwiseAbs().maxCoeff() > 0) continue;
      State ha = a.G_z * f.template head<nx>(), hb = b.G_z * f.template head<nx>();
      if constexpr (nu > 0) {
        ha += a.G_v * f.template tail<nu>();
        hb += b.G_v * f.template tail<nu>();
      }
      worst = std::max(worst, (ha - hb).norm() / fn);
      ++checked;
    }
  }
  if (faces) *faces = checked;
  return worst;
}

}  // namespace saltus
