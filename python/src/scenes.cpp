// The scene library's scenes as Python classes (immutable descriptions: parameters in, read-only
// properties out; they pickle through their parameters) and the simulation options.
#include "common.hpp"

#include <algorithm>
#include <array>
#include <iterator>

namespace saltus::python {

namespace {

const char* friction_name(Friction f) {
  switch (f) {
    case Friction::None: return "none";
    case Friction::Planar: return "planar";
    case Friction::Spatial: return "spatial";
  }
  return "?";
}

Friction friction_from(const std::string& s) {
  if (s == "none") return Friction::None;
  if (s == "planar") return Friction::Planar;
  if (s == "spatial") return Friction::Spatial;
  throw InvalidArgument(detail::concat("friction must be 'none', 'planar' or 'spatial', got '", s, "'"));
}

/// The dimensions and contacts every scene class shows.
template <Scene S, class Cls>
void scene_common(Cls& cls) {
  cls.def_property_readonly_static("nq", [](py::object) { return S::nq; }, "configuration size nq")
      .def_property_readonly_static("nx", [](py::object) { return 2 * S::nq; }, "state size nx = 2 nq: x = (q, v)")
      .def_property_readonly_static("nu", [](py::object) { return S::nu; }, "input size nu")
      .def_property_readonly_static("nc", [](py::object) { return S::nc; }, "number of contacts nc")
      .def_property_readonly_static("name", [](py::object) { return std::string(S::name); })
      .def_property_readonly(
          "contacts",
          [](const S& s) {
            py::list out;
            for (int i = 0; i < S::nc; ++i) {
              const ContactSpec& c = s.contact(i);
              py::dict d;
              d["name"] = c.name;
              d["friction"] = friction_name(c.friction);
              d["mu"] = c.mu;
              d["restitution"] = c.restitution;
              out.append(d);
            }
            return out;
          },
          "the contacts in index order: dicts with name, friction ('none', 'planar', 'spatial'), mu, restitution")
      .def(
          "gaps",
          [](const S& s, const Eigen::VectorXd& q) {
            SALTUS_REQUIRE(q.size() == S::nq, "q has size ", q.size(), ", expected nq = ", S::nq, scene_label<S>());
            SALTUS_REQUIRE(q.allFinite(), "q is not finite");
            const Vec<S::nq> qs = q;
            Eigen::VectorXd out(S::nc);
            for (int i = 0; i < S::nc; ++i) out[i] = s.template gap<double>(i, qs);
            return out;
          },
          py::arg("q"), "(nc,) the normal distance [m] of each contact at the configuration q (nq,): >= 0 when open");
}

/// A parameter struct of doubles pickled as a tuple, in the order of `fields`.
template <class P, std::size_t N>
py::tuple to_tuple(const P& p, double P::*const (&fields)[N]) {
  py::tuple t(N);
  for (std::size_t k = 0; k < N; ++k) t[k] = p.*fields[k];
  return t;
}

template <class P, std::size_t N>
P from_tuple(const py::tuple& t, double P::*const (&fields)[N]) {
  SALTUS_REQUIRE(t.size() == N, "pickled parameters: ", t.size(), " values, expected ", N);
  P p;
  for (std::size_t k = 0; k < N; ++k) p.*fields[k] = t[k].cast<double>();
  return p;
}

using HopperParameters = scenes::HopperParameters;
constexpr double HopperParameters::*hopper_fields[] = {
    &HopperParameters::base_mass,     &HopperParameters::thigh_mass,    &HopperParameters::shank_mass,
    &HopperParameters::thigh_length,  &HopperParameters::shank_length,  &HopperParameters::thigh_com,
    &HopperParameters::shank_com,     &HopperParameters::thigh_inertia, &HopperParameters::shank_inertia,
    &HopperParameters::gravity,       &HopperParameters::mu,            &HopperParameters::restitution};
constexpr const char* hopper_names[] = {"base_mass",    "thigh_mass", "shank_mass",    "thigh_length",
                                        "shank_length", "thigh_com",  "shank_com",     "thigh_inertia",
                                        "shank_inertia", "gravity",   "mu",            "restitution"};
static_assert(std::size(hopper_fields) == std::size(hopper_names));

}  // namespace

void bind_scenes(py::module_& m) {
  using scenes::BouncingBall;
  using scenes::PlankBox;
  using scenes::PointMass;

  py::enum_<IntegratorKind>(m, "IntegratorKind", "The integration backend of the simulator.")
      .value("DormandPrince", IntegratorKind::DormandPrince)
      .value("CvodeBdf", IntegratorKind::CvodeBdf)
      .value("CvodeAdams", IntegratorKind::CvodeAdams);

  py::enum_<InconsistentContactResolution>(
      m, "InconsistentContactResolution",
      "What the simulator does with Painleve's inconsistent configuration (a closed sliding contact with no "
      "consistent contact mode): Refuse (the default: the run raises ContactProblemFailure) or "
      "ImpactWithoutCollision (the tangential impulse of Genot & Brogliato 1999, then the run goes on).")
      .value("Refuse", InconsistentContactResolution::Refuse)
      .value("ImpactWithoutCollision", InconsistentContactResolution::ImpactWithoutCollision);

  py::class_<SimulationOptions>(m, "SimulationOptions",
                                "Options of the event-driven simulation (C++ saltus::SimulationOptions, flattened: "
                                "the integrator's fields are attributes here).")
      .def(py::init<>())
      .def_property(
          "integrator", [](const SimulationOptions& o) { return o.integrator.kind; },
          [](SimulationOptions& o, IntegratorKind k) { o.integrator.kind = k; }, "backend (default DormandPrince)")
      .def_property(
          "relative_tolerance", [](const SimulationOptions& o) { return o.integrator.relative_tolerance; },
          [](SimulationOptions& o, double v) { o.integrator.relative_tolerance = v; }, "default 1e-10")
      .def_property(
          "absolute_tolerance", [](const SimulationOptions& o) { return o.integrator.absolute_tolerance; },
          [](SimulationOptions& o, double v) { o.integrator.absolute_tolerance = v; }, "default 1e-12 (state units)")
      .def_property(
          "max_step", [](const SimulationOptions& o) { return o.integrator.max_step; },
          [](SimulationOptions& o, double v) { o.integrator.max_step = v; }, "s; 0: unlimited")
      .def_property(
          "max_steps", [](const SimulationOptions& o) { return o.integrator.max_steps; },
          [](SimulationOptions& o, long v) { o.integrator.max_steps = v; }, "integrator steps per segment")
      .def_readwrite("simultaneity", &SimulationOptions::simultaneity,
                     "s: guard crossings this close in time form one simultaneous event (default 1e-9)")
      .def_readwrite("max_events", &SimulationOptions::max_events)
      .def_readwrite("rest_velocity", &SimulationOptions::rest_velocity,
                     "m/s: impacts slower than this are inelastic; 0 disables the rest criterion")
      .def_readwrite("zeno_bounces", &SimulationOptions::zeno_bounces,
                     "consecutive geometrically shrinking intervals between touchdowns that signal a Zeno "
                     "accumulation (default 12)")
      .def_readwrite("zeno_completion", &SimulationOptions::zeno_completion,
                     "at a detected accumulation: False (default), the run ends with status 'zeno'; True, it is "
                     "continued past it in the persistent contact mode of the accumulating contacts, from the "
                     "projected limit state at the predicted accumulation time, and recorded in "
                     "Trajectory.zeno_completions (an accumulation predicted at or after t_final ends the run with "
                     "status 'zeno' either way)")
      .def_property(
          "painleve_resolution", [](const SimulationOptions& o) { return o.painleve.resolution; },
          [](SimulationOptions& o, InconsistentContactResolution r) { o.painleve.resolution = r; },
          "Painleve's inconsistent configuration: Refuse (default) or ImpactWithoutCollision (C++ "
          "SimulationOptions::painleve.resolution; docs/simulation.md)")
      .def_readwrite("record_dense_output", &SimulationOptions::record_dense_output)
      .def_readwrite("breakpoints", &SimulationOptions::breakpoints,
                     "s: times where the input law is not smooth (the integrator stops there)")
      .def("__repr__",
           [](const SimulationOptions& o) {
             return py::str("SimulationOptions(integrator={}, relative_tolerance={!r}, absolute_tolerance={!r})")
                 .format(to_string(o.integrator.kind), o.integrator.relative_tolerance, o.integrator.absolute_tolerance);
           })
      .def(py::pickle(
          [](const SimulationOptions& o) {
            return py::make_tuple(static_cast<int>(o.integrator.kind), o.integrator.relative_tolerance,
                                  o.integrator.absolute_tolerance, o.integrator.max_step, o.integrator.max_steps,
                                  o.simultaneity, o.max_events, o.rest_velocity, o.zeno_bounces,
                                  o.record_dense_output, o.breakpoints, o.zeno_completion,
                                  static_cast<int>(o.painleve.resolution));
          },
          [](const py::tuple& t) {
            SimulationOptions o;
            o.integrator.kind = static_cast<IntegratorKind>(t[0].cast<int>());
            o.integrator.relative_tolerance = t[1].cast<double>();
            o.integrator.absolute_tolerance = t[2].cast<double>();
            o.integrator.max_step = t[3].cast<double>();
            o.integrator.max_steps = t[4].cast<long>();
            o.simultaneity = t[5].cast<double>();
            o.max_events = t[6].cast<int>();
            o.rest_velocity = t[7].cast<double>();
            o.zeno_bounces = t[8].cast<int>();
            o.record_dense_output = t[9].cast<bool>();
            o.breakpoints = t[10].cast<std::vector<double>>();
            if (t.size() > 11) o.zeno_completion = t[11].cast<bool>();  // absent from the 11-field pickles
            if (t.size() > 12)  // absent from the 12-field pickles
              o.painleve.resolution = static_cast<InconsistentContactResolution>(t[12].cast<int>());
            return o;
          }));

  // ---- BouncingBall: q = height [m] ----------------------------------------------------------
  py::class_<BouncingBall> ball(m, "BouncingBall",
                                "A ball falling onto the ground: q = height of its lowest point [m], x = (q, v); no "
                                "input (nu = 0), one frictionless contact 'ground' with restitution e_n.");
  ball.def(py::init([](double mass, double gravity, double restitution) {
             return BouncingBall({mass, gravity, restitution});
           }),
           py::arg("mass") = 0.1, py::arg("gravity") = 9.81, py::arg("restitution") = 0.5,
           "mass [kg], gravity [m/s^2], restitution: Newton coefficient e_n in [0, 1]")
      .def_property_readonly("mass", [](const BouncingBall& s) { return s.parameters().mass; })
      .def_property_readonly("gravity", [](const BouncingBall& s) { return s.parameters().gravity; })
      .def_property_readonly("restitution", [](const BouncingBall& s) { return s.parameters().restitution; })
      .def("__repr__",
           [](const BouncingBall& s) {
             const auto& p = s.parameters();
             return py::str("BouncingBall(mass={!r}, gravity={!r}, restitution={!r})").format(p.mass, p.gravity,
                                                                                            p.restitution);
           })
      .def(py::pickle(
          [](const BouncingBall& s) {
            const auto& p = s.parameters();
            return py::make_tuple(p.mass, p.gravity, p.restitution);
          },
          [](const py::tuple& t) {
            return BouncingBall({t[0].cast<double>(), t[1].cast<double>(), t[2].cast<double>()});
          }));
  scene_common<BouncingBall>(ball);

  // ---- PointMass: the guiding example of the time-freezing paper -----------------------------
  py::class_<PointMass> point(m, "PointMass",
                              "The guiding example of the time-freezing paper (Nurkanovic et al. 2023, Example 1): a "
                              "point mass above a table, q = (horizontal position, height) [m], u = thrust [N] (nu = "
                              "2), one contact 'table'.");
  point
      .def(py::init([](double mass, double gravity, const std::string& friction, double mu, double restitution) {
             return PointMass({mass, gravity, friction_from(friction), mu, restitution});
           }),
           py::arg("mass") = 1.0, py::arg("gravity") = 9.81, py::arg("friction") = "none", py::arg("mu") = 0.0,
           py::arg("restitution") = 0.0,
           "mass [kg], gravity [m/s^2], friction: 'none' (Example 1) or 'planar' (Coulomb, coefficient mu), "
           "restitution e_n in [0, 1]")
      .def_property_readonly("mass", [](const PointMass& s) { return s.parameters().mass; })
      .def_property_readonly("gravity", [](const PointMass& s) { return s.parameters().gravity; })
      .def_property_readonly("friction", [](const PointMass& s) { return friction_name(s.parameters().friction); })
      .def_property_readonly("mu", [](const PointMass& s) { return s.parameters().mu; })
      .def_property_readonly("restitution", [](const PointMass& s) { return s.parameters().restitution; })
      .def("__repr__",
           [](const PointMass& s) {
             const auto& p = s.parameters();
             return py::str("PointMass(mass={!r}, gravity={!r}, friction={!r}, mu={!r}, restitution={!r})")
                 .format(p.mass, p.gravity, friction_name(p.friction), p.mu, p.restitution);
           })
      .def(py::pickle(
          [](const PointMass& s) {
            const auto& p = s.parameters();
            return py::make_tuple(p.mass, p.gravity, friction_name(p.friction), p.mu, p.restitution);
          },
          [](const py::tuple& t) {
            return PointMass({t[0].cast<double>(), t[1].cast<double>(), friction_from(t[2].cast<std::string>()),
                              t[3].cast<double>(), t[4].cast<double>()});
          }));
  scene_common<PointMass>(point);

  // ---- PlankBox: a box landing on a compliant plank -------------------------------------------
  py::class_<PlankBox> plank(m, "PlankBox",
                             "A box (mass, length, height) landing on a plank hinged at its left end with a torsion "
                             "spring and damper; q = (box x [m], box y [m], box angle [rad], plank angle [rad]), u = "
                             "(force x [N], force y [N], torque [N m]) on the box; contacts 'C_L', 'C_R' (the box's "
                             "bottom corners, planar Coulomb friction).");
  plank
      .def(py::init([](double box_mass, double box_length, double box_height, double plank_mass, double plank_length,
                       double plank_thickness, double spring, double damper, double gravity, double mu,
                       double restitution) {
             return PlankBox({box_mass, box_length, box_height, plank_mass, plank_length, plank_thickness, spring,
                              damper, gravity, mu, restitution});
           }),
           py::arg("box_mass") = 1.0, py::arg("box_length") = 0.3, py::arg("box_height") = 0.1,
           py::arg("plank_mass") = 2.0, py::arg("plank_length") = 1.0, py::arg("plank_thickness") = 0.02,
           py::arg("spring") = 200.0, py::arg("damper") = 2.0, py::arg("gravity") = 9.81, py::arg("mu") = 0.4,
           py::arg("restitution") = 0.0,
           "masses [kg], lengths [m], spring [N m/rad], damper [N m s/rad], gravity [m/s^2], mu (both corners), "
           "restitution e_n")
      .def("flat_state", &PlankBox::flat_state, py::arg("along") = 0.6, py::arg("clearance") = 0.05,
           "x (nx = 8) of the box level above the plank at rest: `along` [m] from the hinge, `clearance` [m] above it")
      .def("lowering_input", &PlankBox::lowering_input, py::arg("push") = 2.0,
           "u (nu = 3): a vertical force `push` [N] less than the box's weight")
      .def("__repr__",
           [](const PlankBox& s) {
             const auto& p = s.parameters();
             return py::str("PlankBox(box_mass={!r}, plank_mass={!r}, spring={!r}, damper={!r}, mu={!r})")
                 .format(p.box_mass, p.plank_mass, p.spring, p.damper, p.mu);
           })
      .def(py::pickle(
          [](const PlankBox& s) {
            const auto& p = s.parameters();
            return py::make_tuple(p.box_mass, p.box_length, p.box_height, p.plank_mass, p.plank_length,
                                  p.plank_thickness, p.spring, p.damper, p.gravity, p.mu, p.restitution);
          },
          [](const py::tuple& t) {
            PlankBox::Parameters p;
            double* fields[] = {&p.box_mass, &p.box_length,   &p.box_height, &p.plank_mass,
                                &p.plank_length, &p.plank_thickness, &p.spring, &p.damper,
                                &p.gravity,  &p.mu,           &p.restitution};
            for (std::size_t k = 0; k < std::size(fields); ++k) *fields[k] = t[k].cast<double>();
            return PlankBox(p);
          }));
  scene_common<PlankBox>(plank);

  // ---- Hopper: the one-legged hopping robot Capler (time-freezing paper, Section 6) ----------
  using scenes::Hopper;
  py::class_<Hopper> hopper(m, "Hopper",
                            "The planar one-legged hopper (time-freezing paper, Section 6): a base at the hip that "
                            "translates without rotating, a thigh and a shank driven at the hip and the knee; q = (x "
                            "[m], z [m] of the hip, phi_hip [rad] (thigh from the downward vertical), phi_knee [rad] "
                            "(shank relative to the thigh)), u = (tau_hip, tau_knee) [N m]; one contact 'foot' "
                            "(planar Coulomb friction).");
  {
    const HopperParameters d{};
    hopper
        .def(py::init([](double base_mass, double thigh_mass, double shank_mass, double thigh_length,
                         double shank_length, double thigh_com, double shank_com, double thigh_inertia,
                         double shank_inertia, double gravity, double mu, double restitution) {
               return Hopper({base_mass, thigh_mass, shank_mass, thigh_length, shank_length, thigh_com, shank_com,
                              thigh_inertia, shank_inertia, gravity, mu, restitution});
             }),
             py::arg("base_mass") = d.base_mass, py::arg("thigh_mass") = d.thigh_mass,
             py::arg("shank_mass") = d.shank_mass, py::arg("thigh_length") = d.thigh_length,
             py::arg("shank_length") = d.shank_length, py::arg("thigh_com") = d.thigh_com,
             py::arg("shank_com") = d.shank_com, py::arg("thigh_inertia") = d.thigh_inertia,
             py::arg("shank_inertia") = d.shank_inertia, py::arg("gravity") = d.gravity, py::arg("mu") = d.mu,
             py::arg("restitution") = d.restitution,
             "masses [kg], lengths (hip to knee, knee to foot) and centres of mass (from the hip along the thigh, "
             "from the knee along the shank) [m], inertias about the centres of mass [kg m^2], gravity [m/s^2], the "
             "foot's mu and restitution e_n; defaults: the model data of the time-freezing paper's hopper")
        .def_property_readonly("total_mass", &Hopper::total_mass, "kg")
        .def(
            "foot",
            [](const Hopper& s, const Eigen::VectorXd& q) {
              SALTUS_REQUIRE(q.size() == Hopper::nq, "q has size ", q.size(), ", expected nq = ", Hopper::nq,
                             " for the scene hopper");
              return Eigen::Vector2d(s.foot<double>(Vec<Hopper::nq>(q)));
            },
            py::arg("q"), "the foot's position (x, z) [m] at the configuration q (nq = 4,)")
        .def("__repr__",
             [](const Hopper& s) {
               const auto& p = s.parameters();
               return py::str("Hopper(total_mass={!r}, mu={!r}, restitution={!r})")
                   .format(s.total_mass(), p.mu, p.restitution);
             })
        .def(py::pickle([](const Hopper& s) { return to_tuple(s.parameters(), hopper_fields); },
                        [](const py::tuple& t) { return Hopper(from_tuple<HopperParameters>(t, hopper_fields)); }));
    for (std::size_t k = 0; k < std::size(hopper_names); ++k)
      hopper.def_property_readonly(hopper_names[k], [f = hopper_fields[k]](const Hopper& s) { return s.parameters().*f; });
  }
  scene_common<Hopper>(hopper);

  // ---- SpatialBox: a rigid box in space above flat ground, eight corner contacts --------------
  using scenes::SpatialBox;
  py::class_<SpatialBox> box(m, "SpatialBox",
                             "A rigid box above flat ground: q = (x, y, z [m] of the centre, roll, pitch, yaw [rad], "
                             "Z-Y-X Euler angles), no input (nu = 0); eight contacts 'corner0'..'corner7' (spatial "
                             "Coulomb friction), corners 0-3 the bottom face. Euler angles are singular at pitch = "
                             "+-pi/2 (NonSpdMassMatrix).");
  box.def(py::init([](double mass, const std::vector<double>& size, double gravity, double mu, double restitution) {
            SALTUS_REQUIRE(size.size() == 3, "size has ", size.size(), " entries, expected 3 edge lengths [m]");
            return SpatialBox({mass, {size[0], size[1], size[2]}, gravity, mu, restitution});
          }),
          py::arg("mass") = 2.0, py::arg("size") = std::vector<double>{0.4, 0.3, 0.2}, py::arg("gravity") = 9.81,
          py::arg("mu") = 0.5, py::arg("restitution") = 0.0,
          "mass [kg], size: edge lengths along the body x, y, z [m], gravity [m/s^2], mu (every corner), "
          "restitution e_n")
      .def_property_readonly("mass", [](const SpatialBox& s) { return s.parameters().mass; })
      .def_property_readonly("size", [](const SpatialBox& s) { return s.parameters().size; })
      .def_property_readonly("gravity", [](const SpatialBox& s) { return s.parameters().gravity; })
      .def_property_readonly("mu", [](const SpatialBox& s) { return s.parameters().mu; })
      .def_property_readonly("restitution", [](const SpatialBox& s) { return s.parameters().restitution; })
      .def("__repr__",
           [](const SpatialBox& s) {
             const auto& p = s.parameters();
             return py::str("SpatialBox(mass={!r}, size={!r}, gravity={!r}, mu={!r}, restitution={!r})")
                 .format(p.mass, p.size, p.gravity, p.mu, p.restitution);
           })
      .def(py::pickle(
          [](const SpatialBox& s) {
            const auto& p = s.parameters();
            return py::make_tuple(p.mass, p.size, p.gravity, p.mu, p.restitution);
          },
          [](const py::tuple& t) {
            return SpatialBox({t[0].cast<double>(), t[1].cast<std::array<double, 3>>(), t[2].cast<double>(),
                               t[3].cast<double>(), t[4].cast<double>()});
          }));
  scene_common<SpatialBox>(box);
}

}  // namespace saltus::python
