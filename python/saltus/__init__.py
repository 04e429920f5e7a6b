"""Saltus: hybrid mechanical systems with impacts and Coulomb friction, from Python.

The compiled module ``saltus._saltus`` binds the C++ library's scene library:

Scenes (immutable, picklable)
    ``BouncingBall``, ``PointMass`` (the guiding example), ``PlankBox``, ``Hopper`` (the
    one-legged hopper), ``SpatialBox`` (a box on eight corner contacts); ``nq``, ``nx = 2 nq``,
    ``nu``, ``nc``, ``contacts`` and ``gaps(q)`` describe them.
Simulation
    ``simulate(scene, x0, t0, t_final, input=None, options=None)`` returns the scene's
    ``Trajectory``: ``segments`` (``Segment.times`` (n,) s, ``Segment.states`` (n, nx)),
    ``events`` (``Event.t``, ``guards``, ``mode_before``, ``mode_after``, ``x_minus``,
    ``x_plus``), ``sample(times)`` (n, nx), ``inputs(times)`` (n, nu), ``to_json(complete=False)``,
    ``to_csv(dt)``. ``input``: None, a constant u (nu,), or a Python callable ``u(t, x)``.
    ``polish(scene, csv)``: a reference read back from CSV and re-simulated.
    ``read_trajectory(source, scene)``: a trajectory written by ``to_json(complete=True)`` read
    back exactly (segments, dense output, events; not its input law).
    ``references``: the library's reference motions, with their C++ input laws.
Jump gains
    ``jump_gains(trajectory)``: per event ``JumpGain.G_z`` (nx, nx), ``G_v`` (nx, nu),
    ``dt_dz``, ``dt_dv``. ``conewise_gain(trajectory, event)``: the conewise gain of a
    simultaneous event, ``pieces`` (``ConewisePiece.order``, ``G_z``, ``G_v``, ``cone_z``,
    ``cone_v``), ``evaluate(z, v)``.
Linearisation, tracking and stability (the actuated scenes: PointMass, PlankBox, Hopper)
    ``linearise(reference)`` with ``predict(z0, times)`` (the first-order prediction, (n, nx))
    and ``state_transition(t1, t0)`` (nx, nx); ``lqr_design(lin, Q, R, Q_final)`` or
    ``constant_gains(lin, pd_gain(Kp, Kd))``, ``tracking(lin, gains)`` with
    ``check_stability()``, ``check_periodic_stability(period)``, ``monte_carlo(runs)``.
    ``analyse_reference(reference, Q, R, ...)``: all of it in one call (jump gains, LQR design,
    stability check, Monte Carlo batch and their agreement), the report as a dict.
    ``saltus.distributed`` runs Monte Carlo batches and gain sweeps on a Dask cluster.
Optimal references
    ``optimal_control.point_mass_to_the_target(progress=None)``: time-freezing discovery and the
    mode-schedule refinement; the refined reference comes back as a trajectory to analyse.
    ``plank_box_flat_landing``, ``hopper_over_three_holes``, ``hopper_over_one_hole``: discovery,
    refinement and the analysis of the refined reference, as the C++ programs run them. The
    progress lines go to the callable given, or to the logger "saltus".
Errors
    the C++ exception types with their names and messages: ``Error`` (a ``RuntimeError``),
    ``InvalidArgument`` (also a ``ValueError``), ``NumericalFailure``, ``ContactProblemFailure``,
    ``NonSpdMassMatrix``, ``InternalError``, ``GrazingEvent``, ``SimultaneousActivation``,
    ``UnplannedEvent``.

Units are the scenes' (SI: m, rad, s, kg, N, N m); states are x = (q, v).
"""

import numpy as _np

from . import _saltus

__version__ = _saltus.__version__
from ._saltus import (  # noqa: F401  (the public names)
    BouncingBall,
    ConewisePiece,
    ContactProblemFailure,
    Error,
    Event,
    GrazingEvent,
    Hopper,
    InconsistentContactResolution,
    IntegratorKind,
    InternalError,
    InvalidArgument,
    JumpGain,
    MonteCarloReport,
    NonSpdMassMatrix,
    NumericalFailure,
    PeriodicStabilityReport,
    PlankBox,
    PointMass,
    Segment,
    SimulationOptions,
    SimultaneousActivation,
    SpatialBox,
    StabilityReport,
    UnplannedEvent,
    analyse_reference,
    conewise_gain,
    constant_gains,
    jump_gains,
    linearise,
    lqr_design,
    optimal_control,
    polish,
    references,
    simulate,
    tracking,
)

__all__ = [
    "BouncingBall", "PointMass", "PlankBox", "Hopper", "SpatialBox", "SimulationOptions", "IntegratorKind",
    "InconsistentContactResolution",
    "simulate", "polish", "read_trajectory", "references", "Segment", "Event",
    "jump_gains", "JumpGain", "conewise_gain", "ConewisePiece",
    "linearise", "lqr_design", "constant_gains", "pd_gain", "tracking", "analyse_reference", "optimal_control",
    "StabilityReport", "PeriodicStabilityReport", "MonteCarloReport",
    "Error", "InvalidArgument", "NumericalFailure", "ContactProblemFailure", "NonSpdMassMatrix",
    "InternalError", "GrazingEvent", "SimultaneousActivation", "UnplannedEvent",
]


def pd_gain(Kp, Kd):
    """The gain K = -[Kp, Kd] (nu, nx) of a PD law u = ... - Kp (q - q_i) - Kd (v - v_i).

    Kp, Kd: (nu, nq) arrays (N/m and N s/m for translations, N m/rad and N m s/rad for rotations).
    """
    Kp = _np.atleast_2d(_np.asarray(Kp, dtype=float))
    Kd = _np.atleast_2d(_np.asarray(Kd, dtype=float))
    if Kp.shape != Kd.shape:
        raise InvalidArgument(f"pd_gain: Kp has shape {Kp.shape}, Kd {Kd.shape}: they must agree")
    return -_np.hstack([Kp, Kd])


def read_trajectory(source, scene):
    """The trajectory that ``Trajectory.to_json(complete=True)`` (C++: ``to_json`` with
    ``TrajectoryJsonOptions::complete``, ``write_json``) wrote, rebuilt exactly for ``scene``.

    source: the JSON text (a ``str`` starting with ``{``, or ``bytes`` in UTF-8), or a path (``str`` or
    ``os.PathLike``) of
    a file holding it. scene: a scene of the trajectory's class (e.g. ``saltus.PointMass()``); the
    result is that scene's Trajectory, with every segment's times (n,) s and states (n, nx), its
    dense output (``sample`` gives the original's values bit for bit), every event (t s, guards,
    modes, x_minus, x_plus (nx,)) and the Zeno fields. The input law is not in the JSON: ``inputs``
    and the analyses that need the input raise ``saltus.InvalidArgument`` on a scene with inputs.
    Raises ``saltus.InvalidArgument`` naming the key of a JSON it cannot rebuild from (not written
    complete, a missing key, a state of the wrong size, ...; the JSON of another scene's trajectory:
    its states have another size, or its modes another contact count), ``FileNotFoundError`` for a
    missing file, ``TypeError`` for a source that is neither text nor a path, or a scene that is not
    one of saltus' scenes (a scene bound with SALTUS_PYTHON_BIND_SCENE: its module's
    ``trajectory_from_json(scene, text)``).
    """
    import os

    if isinstance(source, (bytes, bytearray)):
        text = source.decode("utf-8")
    elif isinstance(source, str) and source.lstrip().startswith("{"):
        text = source
    elif isinstance(source, (str, os.PathLike)):
        with open(source, encoding="utf-8") as f:
            text = f.read()
    else:
        raise TypeError(f"read_trajectory: source must be JSON text or a path, got {type(source).__name__}")
    return _saltus.trajectory_from_json(scene, text)
