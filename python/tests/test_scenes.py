"""The hopper and the spatial box from Python, against closed forms and the C++ side: the hopper
dropped onto the ground under a joint PD law written in Python (the C++ reference
hopper_push_off with its C++ law: the same events at the same times), its jump gains and an LQR
design; the spatial box dropped flat onto the table (tests/test_simulation.cpp,
SpatialBoxLandsOnFourCornersAndSlidesToRest) and onto one corner (tests/test_jump_gains.cpp,
SpatialBoxCornerImpactsIntoSlipAndStickMatchTheTwin)."""
import math
import pickle

import numpy as np
import pytest

import saltus
from tolerances import tight

G = 9.81


# ---- Hopper ----------------------------------------------------------------------------------


def test_hopper_describes_itself():
    h = saltus.Hopper()
    assert (h.nq, h.nx, h.nu, h.nc) == (4, 8, 2, 1)
    assert h.contacts == [{"name": "foot", "friction": "planar", "mu": 0.8, "restitution": 0.0}]
    assert h.total_mass == pytest.approx(3.975 + 1.782 + 0.548)
    # tests/test_battery_hopper.cpp: the straight leg of 0.2 + 0.2 m under the hip at 0.4 m stands on the ground
    assert h.gaps([0.0, 0.4, 0.0, 0.0]) == pytest.approx([0.0], abs=1e-15)
    np.testing.assert_allclose(h.foot([0.1, 0.5, 0.4, -0.8]),
                               [0.1 + 0.2 * math.sin(0.4) + 0.2 * math.sin(-0.4),
                                0.5 - 0.2 * math.cos(0.4) - 0.2 * math.cos(-0.4)], atol=1e-15)
    back = pickle.loads(pickle.dumps(saltus.Hopper(mu=0.5, base_mass=4.0)))
    assert back.mu == 0.5 and back.base_mass == 4.0 and back.shank_inertia == h.shank_inertia
    with pytest.raises(saltus.InvalidArgument, match="q has size 3, expected nq = 4"):
        h.gaps([0.0, 0.4, 0.0])


def push_off_law(t, x):
    """references::hopper_push_off's joint PD law, in Python: crouched (hip 0.4, knee -0.8 rad, kp
    40 N m/rad, kd 2 N m s/rad), blended around t = 0.3 s (tanh, 10 ms) into a stiff push (hip
    0.15, knee -0.3, kp 150, kd 3)."""
    s = 0.5 * (1.0 + math.tanh((t - 0.3) / 0.01))
    hip, knee, kp, kd = 0.4 + s * (0.15 - 0.4), -0.8 + s * (-0.3 + 0.8), 40.0 + s * 110.0, 2.0 + s * 1.0
    return np.array([kp * (hip - x[2]) - kd * x[6], kp * (knee - x[3]) - kd * x[7]])


def hopper_drop_state(hopper, height=0.05, forwards=0.3):
    """Crouched (hip 0.4, knee -0.8 rad), the foot `height` [m] above the ground, `forwards` [m/s]."""
    q = np.array([0.0, 0.0, 0.4, -0.8])
    q[1] = height - hopper.gaps(q)[0]
    return np.concatenate([q, [forwards, 0.0, 0.0, 0.0]])


@pytest.fixture(scope="module")
def hopper_drop():
    hopper = saltus.Hopper()
    return saltus.simulate(hopper, hopper_drop_state(hopper), 0.0, 0.45, input=push_off_law, options=tight())


def test_hopper_dropped_onto_the_ground_lands_slips_and_lifts_off(hopper_drop):
    events = hopper_drop.events
    # tests/test_jump_gains.cpp (HopperPushOffUnderFeedbackMatchesTheTwin): three events, an impact
    # into stick, stick->slip, release
    assert [e.guards for e in events] == [[(0, "foot", "touchdown")], [(0, "foot", "slip-onset")],
                                         [(0, "foot", "release")]]
    assert events[0].impact and not events[1].impact and not events[2].impact
    assert events[0].contact_modes_after == ["stick"]
    assert events[1].contact_modes_after == ["slip"]
    assert events[2].contact_modes_after == ["open"]
    # In flight the PD law holds the crouch (u = 0 at the targets, at rest): the whole robot falls
    # freely, and the foot lands after sqrt(2 h / g).
    assert events[0].t == pytest.approx(math.sqrt(2 * 0.05 / G), abs=1e-9)
    assert events[0].x_minus[5] == pytest.approx(-math.sqrt(2 * G * 0.05), rel=1e-9)
    assert hopper_drop.status == "completed"


def test_hopper_in_python_matches_the_cpp_reference(hopper_drop):
    ref = saltus.references.hopper_push_off()  # the same start and law, in C++
    assert isinstance(ref, saltus._saltus.HopperTrajectory)
    # a Python law and a C++ law that compute the same numbers: the same steps (3e-15 s, 2e-13 here)
    np.testing.assert_allclose(hopper_drop.event_times, ref.event_times, rtol=0, atol=1e-12)
    np.testing.assert_allclose(hopper_drop.final_state, ref.final_state, rtol=0, atol=1e-10)


def test_hopper_jump_gains_have_the_scene_shapes(hopper_drop):
    gains = saltus.jump_gains(hopper_drop)  # the Python law's feedback enters the state-input guards
    assert len(gains) == 3
    for g, e in zip(gains, hopper_drop.events):
        assert g.t == e.t
        assert g.G_z.shape == (8, 8) and g.G_v.shape == (8, 2)
        assert g.dt_dz.shape == (8,) and g.dt_dv.shape == (2,)
        assert np.all(np.isfinite(g.G_z)) and g.jump_map_residual < 1e-8
    # the same gains as the C++ law's (the feedback differenced the same way: 4e-10 here)
    for g, c in zip(gains, saltus.jump_gains(saltus.references.hopper_push_off())):
        np.testing.assert_allclose(g.G_z, c.G_z, rtol=0, atol=1e-8 * max(1.0, np.abs(c.G_z).max()))
        np.testing.assert_allclose(g.dt_dz, c.dt_dz, rtol=0, atol=1e-8 * max(1.0, np.abs(c.dt_dz).max()))


def test_hopper_lqr_tracking_of_the_push_off():
    ref = saltus.references.hopper_push_off()
    lin = saltus.linearise(ref)
    assert lin.segment_count == 4
    # tests/test_tracking.cpp (ClosedLoopPredictionHasSlopeTwoOnTheHopper): Q = diag(1, 1, 100,
    # 100, 1, 1, 1, 1), R = 0.01 I
    Q = np.diag([1.0, 1.0, 100.0, 100.0, 1.0, 1.0, 1.0, 1.0])
    gains = saltus.lqr_design(lin, Q=Q, R=0.01 * np.eye(2), Q_final=Q)
    assert gains.gain(0, 0.0).shape == (2, 8)
    design = saltus.tracking(lin, gains)
    z = design.propagate(np.full(8, 1e-3), ref.t_end)
    assert z.shape == (8,) and np.all(np.isfinite(z))
    report = design.monte_carlo(runs=2, size=1e-6, threads=1)
    assert report.runs == 2 and report.failed == 0 and report.kept_event_sequence == 2


# ---- SpatialBox ------------------------------------------------------------------------------


def test_spatial_box_describes_itself():
    box = saltus.SpatialBox()
    assert (box.nq, box.nx, box.nu, box.nc) == (6, 12, 0, 8)
    assert [c["name"] for c in box.contacts] == [f"corner{i}" for i in range(8)]
    assert {c["friction"] for c in box.contacts} == {"spatial"}
    assert box.size == [0.4, 0.3, 0.2]
    # flat at rest: the bottom corners (0-3) on the ground, the top ones 0.2 m above
    np.testing.assert_allclose(box.gaps([0, 0, 0.1, 0, 0, 0.3]), [0] * 4 + [0.2] * 4, atol=1e-15)
    back = pickle.loads(pickle.dumps(saltus.SpatialBox(mass=3.0, size=[0.5, 0.4, 0.3], mu=0.2)))
    assert back.mass == 3.0 and back.size == [0.5, 0.4, 0.3] and back.mu == 0.2
    with pytest.raises(saltus.InvalidArgument, match="size has 2 entries"):
        saltus.SpatialBox(size=[0.4, 0.3])


def test_spatial_box_dropped_flat_onto_the_table_lands_on_four_corners_and_slides_to_rest():
    # tests/test_simulation.cpp, SpatialBoxLandsOnFourCornersAndSlidesToRest: dropped flat from
    # h = 0.1 m while sliding at vx = 2 m/s; the impact takes mu times the normal impulse off the
    # sliding speed, the box slides and stops.
    box = saltus.SpatialBox()
    mu, h, vx = box.mu, 0.1, 2.0
    x0 = np.zeros(12)
    x0[2] = 0.5 * box.size[2] + h
    x0[6] = vx
    traj = saltus.simulate(box, x0, 0.0, 1.0, options=tight())
    assert len(traj.events) >= 2
    landing = traj.events[0]
    vn = math.sqrt(2 * G * h)
    assert landing.t == pytest.approx(math.sqrt(2 * h / G), abs=1e-11)
    assert landing.guards == [(i, f"corner{i}", "touchdown") for i in range(4)]
    assert landing.impact
    assert landing.x_plus[6] == pytest.approx(vx - mu * vn, abs=1e-9)  # the C++ test's number
    assert landing.x_plus[8] == pytest.approx(0.0, abs=1e-12)
    t_stop = landing.t + (vx - mu * vn) / (mu * G)
    assert traj.events[1].t == pytest.approx(t_stop, abs=1e-9)
    assert traj.events[1].contact_modes_after[:4] == ["stick"] * 4
    # Four corners that a tilt separates: no single jump gain, the event's gain is conewise.
    with pytest.raises(saltus.SimultaneousActivation):
        saltus.jump_gains(traj)


def test_spatial_box_corner_landing_has_one_jump_gain():
    # tests/test_jump_gains.cpp, SpatialBoxCornerImpactsIntoSlipAndStickMatchTheTwin: tilted about
    # both axes and sliding, the box lands on one corner (an impact into spatial slip or stick),
    # cut before the next landing.
    box = saltus.SpatialBox()
    x0 = np.zeros(12)
    x0[3], x0[4], x0[6], x0[7] = 0.12, -0.17, 0.6, -0.25
    x0[2] = 0.02 - box.gaps(x0[:6])[:4].min()
    probe = saltus.simulate(box, x0, 0.0, 0.12, options=tight())
    t0 = probe.events[0].t
    t_cut = t0 + 0.3 * (probe.events[1].t - t0) if len(probe.events) >= 2 else min(t0 + 0.02, 0.12)
    traj = saltus.simulate(box, x0, 0.0, t_cut, options=tight())
    assert len(traj.events) == 1
    ev = traj.events[0]
    assert len(ev.guards) == 1 and ev.guards[0][2] == "touchdown" and ev.impact
    assert ev.t == pytest.approx(math.sqrt(2 * 0.02 / G), abs=1e-10)  # free fall without rotation
    (gain,) = saltus.jump_gains(traj)
    assert gain.G_z.shape == (12, 12) and gain.G_v.shape == (12, 0)
    assert gain.dt_dz.shape == (12,) and gain.dt_dv.shape == (0,)
    assert np.all(np.isfinite(gain.G_z)) and gain.jump_map_residual < 1e-8
    # the event time moves with the landing corner's height: dt = -dgap / gap_dot at first order
    assert gain.dt_dz[2] == pytest.approx(-1.0 / ev.x_minus[8], rel=1e-6)
