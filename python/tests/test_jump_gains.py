"""Jump gains from Python against the closed form of the bouncing ball's saltation matrix and
against finite differences of simulations (the first-order prediction of a perturbed bounce)."""
import math

import numpy as np
import pytest

import saltus

G = 9.81


def tight():
    o = saltus.SimulationOptions()
    o.relative_tolerance = 1e-13
    o.absolute_tolerance = 1e-13
    return o


def test_bouncing_ball_saltation_matrix_is_the_closed_form():
    e = 0.5
    traj = saltus.simulate(saltus.BouncingBall(restitution=e), [1.0, 0.0], 0.0, 1.0, options=tight())
    gains = saltus.jump_gains(traj)
    assert len(gains) == len(traj.events)
    g = gains[0]
    v_minus = traj.events[0].x_minus[1]
    # G_z = Dg + (f+ - Dg f-) Dgamma_x / gamma_dot with Dg = diag(1, -e), gamma = q, gamma_dot = v-.
    expected = np.array([[-e, 0.0], [-(1 + e) * G / v_minus, -e]])
    assert g.G_z.shape == (2, 2) and g.G_v.shape == (2, 0)
    np.testing.assert_allclose(g.G_z, expected, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(g.dt_dz, [-1.0 / v_minus, 0.0], rtol=1e-10)
    assert g.t == traj.events[0].t


def test_gain_predicts_the_perturbed_bounce():
    """x+(eps) - x+ at the nominal event time, from simulations, is G_z z- to O(eps^2)."""
    e, h0 = 0.5, 1.0
    scene = saltus.BouncingBall(restitution=e)
    nominal = saltus.simulate(scene, [h0, 0.0], 0.0, 0.6, options=tight())
    t_star = nominal.events[0].t
    G_z = saltus.jump_gains(nominal)[0].G_z
    errors = []
    for eps in [1e-3, 1e-4]:
        dz0 = np.array([eps, -0.5 * eps])
        perturbed = saltus.simulate(scene, np.array([h0, 0.0]) + dz0, 0.0, 0.6, options=tight())
        # z- at t*: the free flight is linear in the deviation (the flow of a constant force)
        z_minus = dz0 + np.array([dz0[1] * t_star, 0.0])
        # z+ against the post-event reference extended to t* (it is a parabola through x+)
        x_plus_ref = nominal.events[0].x_plus
        t_late = nominal.events[0].t + 0.05
        x_pert = perturbed.sample([t_late])[0]
        x_ref = nominal.sample([t_late])[0]
        # carry both back to t* along the post-event flow (linear in the state for constant gravity)
        dt = t_late - t_star
        z_plus = (x_pert - x_ref) - np.array([(x_pert - x_ref)[1] * dt, 0.0])
        errors.append(np.linalg.norm(z_plus - G_z @ z_minus))
        assert x_plus_ref[1] > 0
    # second order: the remainder drops by ~100 when eps drops by 10
    assert errors[1] < errors[0] / 50


def test_example3_gains_impact_and_release():
    ref = saltus.references.example3()
    gains = saltus.jump_gains(ref)
    assert [g.G_z.shape for g in gains] == [(4, 4), (4, 4)]
    assert [g.G_v.shape for g in gains] == [(4, 2), (4, 2)]
    impact, release = gains
    # Inelastic frictionless impact: the normal velocity is lost, the tangential one kept.
    assert impact.G_z[3, 3] == pytest.approx(0.0, abs=1e-12)
    assert impact.G_z[2, 2] == pytest.approx(1.0, abs=1e-12)
    # A release under a mode-independent input law: the forces are continuous, G_z = I, G_v = 0.
    np.testing.assert_allclose(release.G_z, np.eye(4), atol=1e-9)
    np.testing.assert_allclose(release.G_v, np.zeros((4, 2)), atol=1e-9)
    # The release guard depends on the input: its time shifts with v (lambda_n = m g - u2).
    assert abs(release.dt_dv[1]) > 0.01


def test_feedback_option_is_checked():
    ref = saltus.references.example3()
    with pytest.raises(saltus.InvalidArgument, match="feedback must be"):
        saltus.jump_gains(ref, feedback="sideways")


def test_simultaneous_touchdowns_raise_simultaneous_activation():
    """The plank-box landing flat touches down on both corners at once: the gain is conewise."""
    box = saltus.PlankBox()
    traj = saltus.simulate(box, box.flat_state(), 0.0, 0.3, input=box.lowering_input(), options=tight())
    assert len(traj.events[0].guards) == 2
    with pytest.raises(saltus.SimultaneousActivation):
        saltus.jump_gains(traj)


def test_flat_landing_has_a_conewise_gain_of_two_pieces():
    """The plank-box landing flat: one piece per touchdown order, each applied on its own cone."""
    box = saltus.PlankBox()
    traj = saltus.simulate(box, box.flat_state(), 0.0, 0.3, input=box.lowering_input(), options=tight())
    gain = saltus.conewise_gain(traj, 0)
    assert gain.t == traj.events[0].t
    assert gain.build_all() == 2
    orders = sorted(tuple(g[0][1] for g in p.order) for p in gain.pieces)
    assert orders == [("C_L", "C_R"), ("C_R", "C_L")]
    a, b = gain.pieces
    assert a.G_z.shape == (8, 8) and a.G_v.shape == (8, 3) and a.cone_z.shape[1] == 8
    assert np.linalg.norm(a.G_z - b.G_z) > 1e-3  # a genuinely conewise map
    rng = np.random.default_rng(20261204)
    seen = set()
    for _ in range(20):
        z, v = rng.standard_normal(8), rng.standard_normal(3)
        p = gain.piece(z, v)
        seen.add(tuple(g[0][1] for g in p.order))
        assert np.all(p.cone_z @ z + p.cone_v @ v >= -1e-12)  # the deviation lies in its piece's cone
        np.testing.assert_allclose(gain.evaluate(z, v), p.G_z @ z + p.G_v @ v, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(gain.evaluate(3.0 * z, 3.0 * v), 3.0 * gain.evaluate(z, v), rtol=1e-12, atol=1e-12)
    assert len(seen) == 2
    with pytest.raises(saltus.InvalidArgument, match="event index 1 out of range"):
        saltus.conewise_gain(traj, 1)
    with pytest.raises(saltus.InvalidArgument, match="z has size 4"):
        gain.evaluate(np.zeros(4))


def test_first_order_prediction_across_events_has_an_eps_squared_remainder():
    """Linearisation.predict on the point mass with friction (impact into slip, slip->stick,
    stick->slip, release): x_eps(t) - x(t) - eps z(t) shrinks like eps^2, and the state-transition
    matrix maps z0 to the same z(t)."""
    ref = saltus.references.point_mass_with_friction()
    law = lambda t, x: np.array([t * t, 2.0 * t * t])  # noqa: E731  (the reference's u, in Python)
    x0 = ref.segments[0].states[0]
    lin = saltus.linearise(ref, spreading=0.05, feedback="closed_loop")
    d = np.array([0.3, -0.5, 0.2, 0.4])
    t_end = ref.t_end
    t = np.array([0.5 * ref.events[0].t, 0.5 * (ref.events[1].t + ref.events[2].t), t_end])
    z = lin.predict(d, t)
    assert z.shape == (3, 4) and len(ref.events) >= 3
    np.testing.assert_allclose(lin.state_transition(t_end, 0.0) @ d, z[2], rtol=1e-7, atol=1e-9)
    remainders = []
    for eps in [1e-4, 1e-5]:
        perturbed = saltus.simulate(ref.scene, x0 + eps * d, 0.0, t_end, input=law, options=ref.options)
        assert len(perturbed.events) == len(ref.events)
        remainders.append(np.abs(perturbed.sample(t) - ref.sample(t) - eps * z).max())
    assert remainders[1] < remainders[0] / 30
    with pytest.raises(saltus.InvalidArgument, match="outside the reference"):
        lin.predict(d, [t_end + 1.0])
