"""The library's exceptions reach Python with their names and messages; bad input raises, never
crashes (docs/bad_input.md's simulation rows)."""
import math
import pickle

import numpy as np
import pytest

import saltus


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
