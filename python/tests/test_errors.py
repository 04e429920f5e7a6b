"""The library's exceptions reach Python with their names and messages; bad input raises, never
crashes: docs/bad_input.md's simulation rows, and the bad arguments of the analysis calls
(conewise_gain, linearise and its prediction, lqr_design, constant_gains, the tracking design's
stability check and Monte Carlo batch, the OCP drivers), each a saltus.InvalidArgument (or the
named type of its row) whose message names the argument."""
import math
import pickle

import numpy as np
import pytest

import saltus
from tolerances import tight


def test_exception_hierarchy():
    assert issubclass(saltus.Error, RuntimeError)
    assert issubclass(saltus.InvalidArgument, saltus.Error)
    assert issubclass(saltus.InvalidArgument, ValueError)
    for name in ["NonSpdMassMatrix", "ContactProblemFailure", "NumericalFailure", "InternalError", "GrazingEvent",
                 "SimultaneousActivation", "UnplannedEvent"]:
        cls = getattr(saltus, name)
        assert issubclass(cls, saltus.Error) and cls.__name__ == name and cls.__module__ == "saltus"


def test_negative_horizon_raises_invalid_argument():
    with pytest.raises(saltus.InvalidArgument, match="t_final"):
        saltus.simulate(saltus.BouncingBall(), [1.0, 0.0], 0.0, -1.0)
    with pytest.raises(saltus.InvalidArgument):
        saltus.simulate(saltus.BouncingBall(), [1.0, 0.0], 2.0, 2.0)


def test_wrong_state_size_names_the_sizes():
    with pytest.raises(saltus.InvalidArgument, match=r"x0 has size 3, expected nx = 2 nq = 2 for the scene bouncing_ball"):
        saltus.simulate(saltus.BouncingBall(), [1.0, 0.0, 0.0], 0.0, 1.0)
    with pytest.raises(saltus.InvalidArgument, match="expected nx = 2 nq = 4"):
        saltus.simulate(saltus.PointMass(), np.zeros(2), 0.0, 1.0)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_initial_state_raises(bad):
    with pytest.raises(saltus.InvalidArgument, match="initial state x0"):
        saltus.simulate(saltus.BouncingBall(), [bad, 0.0], 0.0, 1.0)
    with pytest.raises(saltus.InvalidArgument, match="initial state x0"):
        saltus.simulate(saltus.PointMass(), [0.0, 1.0, bad, 0.0], 0.0, 1.0, input=[0.0, 0.0])


def test_state_below_the_ground_names_the_contact():
    with pytest.raises(saltus.InvalidArgument, match="penetrates contact 'ground'"):
        saltus.simulate(saltus.BouncingBall(), [-0.1, 0.0], 0.0, 1.0)


@pytest.mark.parametrize("kwargs", [{"restitution": 1.5}, {"restitution": -0.1}, {"restitution": math.nan}])
def test_restitution_outside_its_range_names_the_contact(kwargs):
    with pytest.raises(saltus.InvalidArgument, match="ground"):
        saltus.simulate(saltus.BouncingBall(**kwargs), [1.0, 0.0], 0.0, 1.0)


def test_negative_friction_coefficient_raises():
    with pytest.raises(saltus.InvalidArgument, match="table"):
        saltus.simulate(saltus.PointMass(friction="planar", mu=-0.5), [0.0, 1.0, 0.0, 0.0], 0.0, 1.0, input=[0.0, 0.0])
    with pytest.raises(saltus.InvalidArgument, match="friction must be"):
        saltus.PointMass(friction="sticky")


def test_non_positive_tolerances_raise():
    options = saltus.SimulationOptions()
    options.relative_tolerance = 0.0
    with pytest.raises(saltus.InvalidArgument):
        saltus.simulate(saltus.BouncingBall(), [1.0, 0.0], 0.0, 1.0, options=options)


def test_bad_inputs_raise_invalid_argument():
    with pytest.raises(saltus.InvalidArgument, match="constant input has size 3, expected nu = 2"):
        saltus.simulate(saltus.PointMass(), [0.0, 1.0, 0.0, 0.0], 0.0, 1.0, input=[0.0, 0.0, 0.0])
    with pytest.raises(saltus.InvalidArgument, match="the input law returned 1 values"):
        saltus.simulate(saltus.PointMass(), [0.0, 1.0, 0.0, 0.0], 0.0, 1.0, input=lambda t, x: [0.0])
    with pytest.raises(saltus.InvalidArgument, match="the input law must return 2 numbers"):
        saltus.simulate(saltus.PointMass(), [0.0, 1.0, 0.0, 0.0], 0.0, 1.0, input=lambda t, x: "up")
    with pytest.raises(saltus.InvalidArgument, match="input must be None, a callable"):
        saltus.simulate(saltus.PointMass(), [0.0, 1.0, 0.0, 0.0], 0.0, 1.0, input="up")


def test_an_input_law_returning_nan_is_a_numerical_failure():
    with pytest.raises(saltus.NumericalFailure, match="not finite"):
        saltus.simulate(saltus.PointMass(), [0.0, 1.0, 0.0, 0.0], 0.0, 1.0, input=lambda t, x: np.array([math.nan, 0.0]))


def test_non_spd_mass_matrix_raises_its_type():
    box = saltus.PlankBox(box_mass=-1.0)
    with pytest.raises(saltus.NonSpdMassMatrix, match="not symmetric positive definite"):
        saltus.simulate(box, saltus.PlankBox().flat_state(), 0.0, 0.3)


def test_an_input_law_that_raises_reaches_the_caller():
    def law(t, x):
        if t > 0.2:
            raise KeyError("from the law")
        return np.zeros(2)

    with pytest.raises(KeyError, match="from the law"):
        saltus.simulate(saltus.PointMass(), [0.0, 1.0, 0.0, 0.0], 0.0, 1.0, input=law)


def test_sampling_outside_the_trajectory_raises():
    traj = saltus.simulate(saltus.BouncingBall(restitution=0.0), [1.0, 0.0], 0.0, 1.0)
    with pytest.raises(saltus.InvalidArgument, match="outside the trajectory"):
        traj.sample([1.5])
    with pytest.raises(saltus.InvalidArgument, match="dt must be > 0"):
        traj.to_csv(0.0)


def test_exceptions_pickle_with_their_type_and_message():
    try:
        saltus.simulate(saltus.BouncingBall(), [1.0, 0.0, 0.0], 0.0, 1.0)
    except saltus.InvalidArgument as e:
        back = pickle.loads(pickle.dumps(e))
        assert type(back) is saltus.InvalidArgument and str(back) == str(e)
    else:
        pytest.fail("no exception")


# ---- The analysis calls: conewise_gain, linearise, lqr_design, tracking, monte_carlo, OCPs ----

NAN = math.nan


@pytest.fixture(scope="module")
def flat_landing():
    """The plank-box landing flat on both corners at once (a simultaneous event: conewise gain)."""
    box = saltus.PlankBox()
    return saltus.simulate(box, box.flat_state(), 0.0, 0.3, input=box.lowering_input(), options=tight())


@pytest.fixture(scope="module")
def example3():
    ref = saltus.references.example3()  # impact, sliding, release on [0, 2] s; nx = 4, nu = 2
    lin = saltus.linearise(ref)
    design = saltus.tracking(lin, saltus.lqr_design(lin, R=0.1 * np.eye(2)))
    return ref, lin, design


def test_conewise_gain_refuses_an_event_index_out_of_range(flat_landing):
    for bad in [-1, len(flat_landing.events)]:
        with pytest.raises(saltus.InvalidArgument, match=f"event index {bad} out of range"):
            saltus.conewise_gain(flat_landing, bad)


def test_conewise_gain_refuses_an_event_fired_by_an_input_jump():
    # docs/bad_input.md: a conewise gain of an event without a guarded crossing (its time is fixed)
    options = saltus.SimulationOptions()
    options.breakpoints = [0.5]
    g = 9.81
    traj = saltus.simulate(saltus.PointMass(), [0.0, 0.0, 0.2, 0.0], 0.0, 1.0,
                           input=lambda t, x: np.array([1.0, g / 2 if t < 0.5 else 2 * g]), options=options)
    assert traj.events[0].input_jump
    with pytest.raises(saltus.InvalidArgument, match="fired by a jump of the input"):
        saltus.conewise_gain(traj, 0)


@pytest.mark.parametrize("method", ["evaluate", "piece"])
def test_conewise_gain_deviations_of_the_wrong_size_or_not_finite(flat_landing, method):
    gain = getattr(saltus.conewise_gain(flat_landing, 0), method)
    with pytest.raises(saltus.InvalidArgument, match="z has size 3, expected nx = 2 nq = 8"):
        gain(np.zeros(3))
    with pytest.raises(saltus.InvalidArgument, match="v has size 2, expected nu = 3"):
        gain(np.zeros(8), np.zeros(2))
    with pytest.raises(saltus.InvalidArgument, match=r"the deviation \(z-, v\) is not finite"):
        gain(np.full(8, NAN))
    with pytest.raises(saltus.InvalidArgument, match=r"the deviation \(z-, v\) is not finite"):
        gain(np.ones(8), np.array([0.0, math.inf, 0.0]))


@pytest.mark.parametrize("spreading", [0.0, -0.1, NAN, math.inf])
def test_linearise_refuses_a_spreading_out_of_range(spreading):
    # docs/bad_input.md: reference-spreading options out of range
    with pytest.raises(saltus.InvalidArgument, match="spreading must be > 0"):
        saltus.linearise(saltus.references.example3(), spreading=spreading)


def test_linearise_refuses_an_unknown_feedback_treatment():
    with pytest.raises(saltus.InvalidArgument, match="feedback must be 'signal' or 'closed_loop', got 'open'"):
        saltus.linearise(saltus.references.example3(), feedback="open")


def test_prediction_refuses_bad_deviations_and_times(example3):
    _, lin, _ = example3
    with pytest.raises(saltus.InvalidArgument, match="z0 has size 3, expected nx = 2 nq = 4"):
        lin.predict(np.zeros(3), [0.5])
    with pytest.raises(saltus.InvalidArgument, match="z0 is not finite"):
        lin.predict(np.array([0.0, NAN, 0.0, 0.0]), [0.5])
    with pytest.raises(saltus.InvalidArgument, match="v has size 3, expected nu = 2"):
        lin.predict(np.zeros(4), [0.5], v=np.zeros(3))
    with pytest.raises(saltus.InvalidArgument, match="v is not finite"):
        lin.predict(np.zeros(4), [0.5], v=np.array([NAN, 0.0]))
    # docs/bad_input.md: the extended reference queried outside its interval
    for t in [5.0, -1.0, NAN]:
        with pytest.raises(saltus.InvalidArgument, match="prediction time .* is outside the reference"):
            lin.predict(np.zeros(4), [0.5, t])
    with pytest.raises(saltus.InvalidArgument, match="state_transition: t1 = 0.1.* < t0 = 0.5"):
        lin.state_transition(0.1, 0.5)
    with pytest.raises(saltus.InvalidArgument, match="state_transition: t1 = nan"):
        lin.state_transition(NAN, 0.0)
    with pytest.raises(saltus.InvalidArgument, match="outside the extended segment"):
        lin.state_transition(9.0, 0.0)
    for bad in [-1, 2]:
        with pytest.raises(saltus.InvalidArgument, match=f"event index {bad} out of range"):
            lin.conewise(bad)


def test_state_transition_across_a_simultaneous_event_is_refused(flat_landing):
    # docs/bad_input.md: state_transition() across a simultaneous event
    lin = saltus.linearise(flat_landing)
    assert lin.conewise(0)
    assert lin.state_transition(0.1, 0.0).shape == (8, 8)
    with pytest.raises(saltus.SimultaneousActivation, match="is simultaneous"):
        lin.state_transition(0.3, 0.0)


def test_lqr_design_refuses_weights_of_the_wrong_shape(example3):
    _, lin, _ = example3
    with pytest.raises(saltus.InvalidArgument, match=r"Q has shape \(3, 3\), expected \(4, 4\)"):
        saltus.lqr_design(lin, Q=np.eye(3))
    with pytest.raises(saltus.InvalidArgument, match=r"R has shape \(4, 4\), expected \(2, 2\)"):
        saltus.lqr_design(lin, R=np.eye(4))
    with pytest.raises(saltus.InvalidArgument, match=r"Q_final has shape \(4, 2\), expected \(4, 4\)"):
        saltus.lqr_design(lin, Q_final=np.ones((4, 2)))


def test_lqr_design_refuses_weights_that_are_not_finite_or_not_definite(example3):
    _, lin, _ = example3
    with pytest.raises(saltus.InvalidArgument, match="lqr_design: Q must be finite and symmetric"):
        saltus.lqr_design(lin, Q=np.diag([1.0, 1.0, NAN, 1.0]))
    with pytest.raises(saltus.InvalidArgument, match="lqr_design: Q_final must be finite and symmetric"):
        saltus.lqr_design(lin, Q_final=np.full((4, 4), math.inf))
    with pytest.raises(saltus.InvalidArgument, match="lqr_design: R must be finite and symmetric"):
        saltus.lqr_design(lin, R=np.full((2, 2), NAN))
    with pytest.raises(saltus.InvalidArgument, match="lqr_design: Q must be finite and symmetric"):
        saltus.lqr_design(lin, Q=np.eye(4) + np.triu(np.ones((4, 4)), 1))
    with pytest.raises(saltus.InvalidArgument, match="lqr_design: Q must be positive semidefinite"):
        saltus.lqr_design(lin, Q=-np.eye(4))
    for R in [np.diag([1.0, -1.0]), np.zeros((2, 2))]:
        with pytest.raises(saltus.InvalidArgument, match="lqr_design: R is not positive definite"):
            saltus.lqr_design(lin, R=R)


@pytest.mark.parametrize("step", [0.0, -1e-3, NAN])
def test_lqr_design_refuses_a_sample_step_out_of_range(example3, step):
    with pytest.raises(saltus.InvalidArgument, match="sample_step must be > 0"):
        saltus.lqr_design(example3[1], sample_step=step)


def test_lqr_design_needs_the_signal_linearisation():
    lin = saltus.linearise(saltus.references.example3(), feedback="closed_loop")
    with pytest.raises(saltus.InvalidArgument, match="lqr_design: the LinearisedSystem must linearise the reference"):
        saltus.lqr_design(lin)


def test_constant_gains_and_schedules_refuse_bad_gains(example3):
    _, lin, _ = example3
    with pytest.raises(saltus.InvalidArgument, match=r"the gain has shape \(2, 3\), expected \(nu, nx\) = \(2, 4\)"):
        saltus.constant_gains(lin, np.zeros((2, 3)))
    with pytest.raises(saltus.InvalidArgument, match="the gain K is not finite"):
        saltus.constant_gains(lin, saltus.pd_gain([[1.0, 0.0], [0.0, NAN]], np.eye(2)))
    with pytest.raises(saltus.InvalidArgument, match="pd_gain: Kp has shape"):
        saltus.pd_gain(np.eye(2), np.eye(3))
    Schedule = saltus._saltus.PointMassGainSchedule
    for bad in [0, -1]:
        with pytest.raises(saltus.InvalidArgument, match=f"segments must be >= 1, got {bad}"):
            Schedule(bad, np.zeros((2, 4)))
    with pytest.raises(saltus.InvalidArgument, match="segment 9 out of range"):
        saltus.constant_gains(lin, np.zeros((2, 4))).times(9)
    with pytest.raises(saltus.InvalidArgument, match="the gain schedule has 2 segments, the reference 3"):
        saltus.tracking(lin, Schedule(2, np.zeros((2, 4))))


@pytest.mark.parametrize("kwargs, message", [
    ({"runs": 0}, "monte_carlo: runs must be >= 1, got 0"),
    ({"runs": -5}, "monte_carlo: runs must be >= 1, got -5"),
    ({"runs": 10, "count": -1}, r"monte_carlo: the chunk \[0, -1\) is not a non-empty part of the batch \[0, 10\)"),
    ({"runs": 10, "count": 0}, r"the chunk \[0, 0\) is not a non-empty part"),
    ({"runs": 10, "first": -1}, r"the chunk \[-1, 10\) is not a non-empty part"),
    ({"runs": 10, "first": 8, "count": 5}, r"the chunk \[8, 13\) is not a non-empty part"),
    ({"size": 0.0}, "monte_carlo: size must be > 0, got 0"),
    ({"size": -1e-4}, "monte_carlo: size must be > 0"),
    ({"size": NAN}, "monte_carlo: size must be > 0, got nan"),
    ({"scale": np.ones(3)}, "monte_carlo: scale has size 3, expected nx = 4"),
    ({"scale": np.array([1.0, NAN, 1.0, 1.0])}, "monte_carlo: the scale must be finite"),
    ({"scale": np.zeros(4)}, "monte_carlo: perturbation 0 is zero or not finite"),
    ({"threads": -1}, "monte_carlo: threads must be >= 0"),
    ({"seed": -1}, r"seed must be an integer in \[0, 2\^64\), got -1"),
    ({"seed": 2**64}, r"seed must be an integer in \[0, 2\^64\)"),
    ({"seed": 1.5}, r"seed must be an integer in \[0, 2\^64\), got 1.5"),
    ({"t_final": NAN}, r"monte_carlo: t_final must be a time in the reference \(0, 2\] s, got nan"),
    ({"t_final": -1.0}, "monte_carlo: t_final must be a time in the reference"),
    ({"t_final": 0.0}, "monte_carlo: t_final must be a time in the reference"),
    ({"t_final": 99.0}, "monte_carlo: t_final must be a time in the reference .* got 99"),
    ({"weight": np.eye(3)}, r"weight has shape \(3, 3\), expected \(4, 4\)"),
    ({"weight": np.full((4, 4), NAN)}, "monte_carlo: the weight W must be finite and symmetric"),
    ({"weight": -np.eye(4)}, "monte_carlo: the weight W is not positive definite"),
    ({"output_weight": np.eye(2)}, r"output_weight has shape \(2, 2\), expected \(4, 4\)"),
])
def test_monte_carlo_refuses_bad_arguments(example3, kwargs, message):
    design = example3[2]
    kwargs = {"runs": 2, **kwargs}
    with pytest.raises(saltus.InvalidArgument, match=message):
        design.monte_carlo(**kwargs)


def test_monte_carlo_takes_a_numpy_seed(example3):
    design = example3[2]
    a = design.monte_carlo(runs=2, threads=1, seed=np.uint64(7))
    b = design.monte_carlo(runs=2, threads=1, seed=7)
    np.testing.assert_array_equal(a.observed, b.observed)


def test_perturbations_refuse_bad_arguments(example3):
    design = example3[2]
    with pytest.raises(saltus.InvalidArgument, match="perturbations: runs must be >= 1, got -1"):
        design.perturbations(-1)
    with pytest.raises(saltus.InvalidArgument, match="perturbations: the scale must be finite"):
        design.perturbations(2, np.full(4, NAN))
    with pytest.raises(saltus.InvalidArgument, match="seed must be an integer"):
        design.perturbations(2, seed=-3)
    with pytest.raises(saltus.InvalidArgument, match="MonteCarloReport.merge: no reports"):
        saltus.MonteCarloReport.merge([])


def test_stability_checks_and_propagation_refuse_bad_arguments(example3):
    design = example3[2]
    for t in [NAN, -1.0, 99.0]:
        with pytest.raises(saltus.InvalidArgument, match="check_stability: t_final must be a time in the reference"):
            design.check_stability(t_final=t)
    with pytest.raises(saltus.InvalidArgument, match="check_stability: the weight W must be finite and symmetric"):
        design.check_stability(weight=np.full((4, 4), NAN))
    with pytest.raises(saltus.InvalidArgument, match=r"weight has shape \(2, 2\), expected \(4, 4\)"):
        design.check_stability(weight=np.eye(2))
    for period in [-1.0, NAN, 5.0]:
        with pytest.raises(saltus.InvalidArgument, match="check_periodic_stability: the period"):
            design.check_periodic_stability(period)
    with pytest.raises(saltus.InvalidArgument, match="propagate: z0 is not finite"):
        design.propagate(np.full(4, NAN), 1.0)
    with pytest.raises(saltus.InvalidArgument, match="z0 has size 5, expected nx = 2 nq = 4"):
        design.propagate(np.zeros(5), 1.0)
    for t in [NAN, 99.0, -1.0]:
        with pytest.raises(saltus.InvalidArgument, match="propagate: t = .* is outside the reference"):
            design.propagate(np.zeros(4), t)


def test_ocp_drivers_refuse_bad_arguments_before_solving():
    # docs/bad_input.md: analyse_reference options (runs < 1) refused before any stage runs
    oc = saltus.optimal_control
    with pytest.raises(saltus.InvalidArgument, match="progress must be a callable"):
        oc.point_mass_to_the_target(progress=5)
    with pytest.raises(saltus.InvalidArgument, match="progress must be a callable"):
        oc.plank_box_flat_landing(progress="log")
    with pytest.raises(saltus.InvalidArgument, match="max_edits must be >= 0, got -1"):
        oc.plank_box_flat_landing(max_edits=-1)
    for runs in [0, -3]:
        with pytest.raises(saltus.InvalidArgument, match=f"runs must be >= 1, got {runs}"):
            oc.plank_box_flat_landing(runs=runs)
    with pytest.raises(saltus.InvalidArgument, match="runs must be >= 1, got 0"):
        oc.hopper_over_one_hole(runs=0)
    with pytest.raises(saltus.InvalidArgument, match="deviation_times must be >= 0, got -2"):
        oc.hopper_over_three_holes(deviation_times=-2)
    with pytest.raises(saltus.InvalidArgument, match="initialisation must be 'paper' or 'hop_guess', got 'guess'"):
        oc.hopper_over_three_holes(initialisation="guess")
    with pytest.raises(saltus.InvalidArgument, match="progress must be a callable"):
        oc.hopper_over_one_hole(progress=1.5)


@pytest.mark.parametrize("kwargs, message", [
    ({"Q": np.eye(3)}, r"Q has shape \(3, 3\), expected \(4, 4\)"),
    ({"R": np.eye(4)}, r"R has shape \(4, 4\), expected \(2, 2\)"),
    ({"Q_final": np.ones((4, 1))}, r"Q_final has shape \(4, 1\), expected \(4, 4\)"),
    ({"spreading": -0.1}, "spreading"),
    ({"spreading": NAN}, "spreading"),
    ({"sample_step": 0.0}, "sample_step must be > 0 s, got 0"),
    ({"weight": np.eye(2)}, r"weight has shape \(2, 2\), expected \(4, 4\)"),
    ({"output_weight": np.eye(5)}, r"output_weight has shape \(5, 5\), expected \(4, 4\)"),
    ({"initial_subspace": np.ones((3, 1))}, r"initial_subspace has shape \(3, 1\), expected \(nx, r\) = \(4, r\)"),
    ({"initial_subspace": np.zeros((4, 0))}, r"initial_subspace has shape \(4, 0\)"),
    ({"initial_subspace": np.full((4, 1), NAN)}, "initial_subspace is not finite"),
    ({"initial_subspace": np.ones((4, 2))}, "initial_subspace must have full column rank 2, has rank 1"),
    ({"runs": 0}, "runs"),
    ({"size": 0.0}, "size"),
    ({"scale": np.ones(3)}, "scale has size 3, expected nx = 2 nq = 4"),
    ({"scale": np.full(4, NAN)}, "scale is not finite"),
    ({"threads": -1}, "threads must be >= 0"),
    ({"seed": -1}, r"seed must be an integer in \[0, 2\^64\), got -1"),
    ({"t_final": 99.0}, r"t_final must be a time in the reference \(0, 2\] s, got 99"),
    ({"t_final": NAN}, "t_final must be a time in the reference"),
    ({"progress": 3}, "progress must be a callable"),
])
def test_analyse_reference_refuses_bad_arguments_before_any_stage(example3, kwargs, message):
    ref = example3[0]
    kwargs = {"runs": 2, "threads": 1, "progress": lambda line: None, **kwargs}
    with pytest.raises(saltus.InvalidArgument, match=message):
        saltus.analyse_reference(ref, **kwargs)
