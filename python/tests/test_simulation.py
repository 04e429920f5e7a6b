"""Simulation from Python against closed forms: the bouncing ball's flights and its Zeno time, the
trajectory's segments, events, dense sampling, JSON and CSV, Python input laws against C++ ones."""
import json
import math
import pickle

import numpy as np
import pytest

import saltus
from tolerances import tight

G = 9.81


@pytest.fixture(scope="module")
def ball_trajectory():
    return saltus.simulate(saltus.BouncingBall(restitution=0.5), np.array([1.0, 0.0]), 0.0, 5.0, options=tight())


def test_the_package_says_its_version():
    parts = saltus.__version__.split(".")
    assert len(parts) == 3 and all(p.isdigit() for p in parts)


def test_bouncing_ball_hits_the_ground_at_the_free_fall_time(ball_trajectory):
    ev = ball_trajectory.events[0]
    assert ev.t == pytest.approx(math.sqrt(2.0 / G), abs=1e-10)
    assert ev.guards == [(0, "ground", "touchdown")]
    assert ev.impact
    assert ev.x_minus[0] == pytest.approx(0.0, abs=1e-12)
    assert ev.x_plus[1] == pytest.approx(-0.5 * ev.x_minus[1], rel=1e-12)


def test_bouncing_ball_ends_zeno_at_the_closed_form_time(ball_trajectory):
    t_inf = math.sqrt(2.0 / G) * 1.5 / 0.5
    assert ball_trajectory.status == "zeno"
    assert abs(ball_trajectory.zeno_time - t_inf) < 1e-6
    # 12 bounces: once a bounce's approach speed times its interval is below 1e3 gap tolerances,
    # 4 interval ratios suffice to detect the accumulation (docs/bad_input.md)
    assert len(ball_trajectory.events) >= 12
    # the stated uncertainty is the extrapolation's part (4e-16 s here) plus the integration's (the
    # touchdown times' error: 4 relative tolerances of the time integrated, 5.6e-12 s here) and bounds
    # the distance to the closed form (3e-14 s here: the flights are polynomials, integrated exactly)
    traj = ball_trajectory
    assert 0.0 <= traj.zeno_time_uncertainty < 1e-6
    assert traj.zeno_time_uncertainty == traj.zeno_time_extrapolation_uncertainty + traj.zeno_time_integration_uncertainty
    assert 0.0 < traj.zeno_time_extrapolation_uncertainty < traj.zeno_time_integration_uncertainty
    assert abs(traj.zeno_time - t_inf) <= traj.zeno_time_uncertainty
    stats = ball_trajectory.statistics
    assert stats["sliding_events"] == 0 and stats["ambiguous_selections"] == 0
    assert all(s.sliding_contact == -1 for s in ball_trajectory.segments)


def test_segments_are_arrays_that_meet_the_events(ball_trajectory):
    segments = ball_trajectory.segments
    events = ball_trajectory.events
    assert len(segments) == len(ball_trajectory) == len(events) + 1 or len(segments) == len(events)
    for i, s in enumerate(segments):
        assert s.times.ndim == 1 and s.states.shape == (s.times.size, 2)
        assert s.times[0] == s.t_begin and s.times[-1] == s.t_end
        assert np.all(np.diff(s.times) > 0)
        if i < len(events):
            np.testing.assert_allclose(s.states[-1], events[i].x_minus, atol=1e-12)
        if i > 0:
            np.testing.assert_allclose(s.states[0], events[i - 1].x_plus, atol=1e-12)
    np.testing.assert_array_equal(segments[0].states[0], [1.0, 0.0])
    assert segments[0].contact_modes == ["open"]


def test_dense_sampling_follows_the_parabola(ball_trajectory):
    t = np.linspace(0.0, math.sqrt(2.0 / G) * 0.999, 50)
    x = ball_trajectory.sample(t)
    assert x.shape == (50, 2)
    np.testing.assert_allclose(x[:, 0], 1.0 - 0.5 * G * t**2, atol=1e-9)
    np.testing.assert_allclose(x[:, 1], -G * t, atol=1e-9)
    # At an event time: the state after the event.
    t1 = ball_trajectory.events[0].t
    np.testing.assert_allclose(ball_trajectory.sample([t1])[0], ball_trajectory.events[0].x_plus, atol=1e-9)


def test_json_and_csv_are_the_cpp_writers(ball_trajectory):
    j = json.loads(ball_trajectory.to_json())
    assert j["status"] == "zeno"
    assert len(j["events"]) == len(ball_trajectory.events)
    assert j["events"][0]["guards"] == [{"contact": "ground", "kind": "touchdown"}]
    assert j["events"][0]["t"] == ball_trajectory.events[0].t
    csv = ball_trajectory.to_csv(0.01).splitlines()
    assert csv[0] == "t,segment,mode,q0,v0"
    first = csv[1].split(",")
    assert float(first[0]) == 0.0 and float(first[3]) == 1.0


def test_example3_reference_has_its_impact_and_release():
    ref = saltus.references.example3()
    assert ref.scene.nu == 2 and ref.scene.nx == 4
    times = ref.event_times
    assert times.shape == (2,)
    assert times[0] == pytest.approx(math.sqrt(2.0 / G), abs=1e-10)
    assert times[1] == pytest.approx(1.5, abs=1e-8)
    assert ref.events[1].guards == [(0, "table", "release")]
    assert ref.events[0].mode_after == "table:closed"
    u = ref.inputs(np.array([0.5, 1.25]))
    np.testing.assert_allclose(u, [[7.0, 0.0], [7.0, 2 * G * 0.25]], atol=1e-12)


def test_python_input_law_matches_the_cpp_reference():
    """Example 3's input written in Python reproduces the C++ reference's events and states."""
    ref = saltus.references.example3()

    def u(t, x):
        return np.array([7.0, 0.0 if t < 1.0 else 2.0 * G * (t - 1.0)])

    options = ref.options
    options.breakpoints = [1.0]
    traj = saltus.simulate(ref.scene, [0.0, 1.0, 0.0, 0.0], 0.0, 2.0, input=u, options=options)
    np.testing.assert_allclose(traj.event_times, ref.event_times, atol=1e-9)
    np.testing.assert_allclose(traj.final_state, ref.final_state, rtol=1e-8, atol=1e-8)


def test_a_release_by_an_input_jump_is_marked_and_exact():
    """A point mass at rest on the table under a thrust g/2 that jumps to 2 g at the breakpoint 0.5:
    the contact would pull under the new input, so it releases AT the breakpoint (input_jump, a
    fixed-time event), and the mass rises with y'' = g: y(1) = g/8, y'(1) = g/2 (closed forms)."""
    options = tight()
    options.breakpoints = [0.5]
    traj = saltus.simulate(saltus.PointMass(), [0.0, 0.0, 0.0, 0.0], 0.0, 1.0,
                           input=lambda t, x: np.array([0.0, 0.5 * G if t < 0.5 else 2.0 * G]), options=options)
    assert len(traj.events) == 1
    release = traj.events[0]
    assert release.t == 0.5 and release.input_jump and not release.impact
    assert release.guards == [(0, "table", "release")]
    assert traj.final_state[1] == pytest.approx(G / 8.0, abs=1e-10)
    assert traj.final_state[3] == pytest.approx(G / 2.0, abs=1e-10)
    assert json.loads(traj.to_json())["events"][0]["input_jump"] is True
    ball = saltus.simulate(saltus.BouncingBall(restitution=0.5), np.array([1.0, 0.0]), 0.0, 1.0)
    assert not ball.events[0].input_jump  # a touchdown is a crossing


def test_constant_input_and_python_callable_agree():
    scene = saltus.PointMass(friction="planar", mu=0.5)
    x0 = [0.0, 0.3, 2.0, 0.0]
    a = saltus.simulate(scene, x0, 0.0, 2.0, input=[1.0, 3.0])
    b = saltus.simulate(scene, x0, 0.0, 2.0, input=lambda t, x: np.array([1.0, 3.0]))
    assert [e.t for e in a.events] == [e.t for e in b.events]
    np.testing.assert_array_equal(a.final_state, b.final_state)
    assert [e.mode_after for e in a.events] == ["table:slip+", "table:stick"]


def test_plank_box_reference_has_named_corner_modes():
    ref = saltus.references.plank_box()
    assert [c["name"] for c in ref.scene.contacts] == ["C_L", "C_R"]
    assert ref.events[0].guards[0][1] == "C_R"
    assert ref.events[-1].mode_after == "C_L:stick C_R:stick"


def test_scenes_and_options_pickle():
    for scene in [saltus.BouncingBall(restitution=0.3), saltus.PointMass(friction="planar", mu=0.2), saltus.PlankBox(mu=0.7)]:
        back = pickle.loads(pickle.dumps(scene))
        assert repr(back) == repr(scene)
    o = tight()
    o.breakpoints = [0.5]
    o.zeno_completion = True
    o.zeno_bounces = 20
    back = pickle.loads(pickle.dumps(o))
    assert back.relative_tolerance == 1e-12 and back.breakpoints == [0.5]
    assert back.zeno_completion is True and back.zeno_bounces == 20
    assert saltus.SimulationOptions().zeno_completion is False  # the C++ default
    assert saltus.SimulationOptions().painleve_resolution == saltus.InconsistentContactResolution.Refuse
    o.painleve_resolution = saltus.InconsistentContactResolution.ImpactWithoutCollision
    back = pickle.loads(pickle.dumps(o))
    assert back.painleve_resolution == saltus.InconsistentContactResolution.ImpactWithoutCollision


def test_bouncing_ball_with_zeno_completion_rests_on_the_ground_past_its_accumulation(ball_trajectory):
    """As ZenoCompletion.OneBallOnASpringRestsPastItsAccumulation in C++: continued past the
    accumulation at the closed-form t_inf = sqrt(2 h / g) (1 + e) / (1 - e) (within the stated
    uncertainty), the ball rests on the ground in persistent contact until t_final."""
    t_inf = math.sqrt(2.0 / G) * 1.5 / 0.5
    for bounces in (12, 40):
        o = tight()
        o.zeno_completion = True
        o.zeno_bounces = bounces
        traj = saltus.simulate(saltus.BouncingBall(restitution=0.5), [1.0, 0.0], 0.0, 5.0, options=o)
        assert traj.status == "completed"
        assert traj.t_end == 5.0
        (z,) = traj.zeno_completions
        assert z["contacts"] == ["ground"] and z["contact_indices"] == [0]
        assert abs(z["t"] - t_inf) <= z["uncertainty"] + 1e-12
        assert z["uncertainty"] < 1e-9
        assert z["last_touchdown"] < z["t"]
        assert traj.zeno_time == z["t"]
        completion = traj.events[z["event"]]
        assert completion.t == z["t"] and completion.guards == []
        assert traj.segments[-1].mode == "ground:closed"
        np.testing.assert_array_equal(traj.final_state, [0.0, 0.0])
        rest = traj.sample(np.linspace(z["t"] + 1e-6, 5.0, 20))
        assert np.abs(rest).max() <= 1e-12  # at rest on the ground, in contact
        # Without completion the same run stops at the accumulation.
        assert ball_trajectory.status == "zeno" and ball_trajectory.zeno_completions == []
        j = json.loads(traj.to_json())
        assert j["zeno_completions"][0]["contacts"] == ["ground"] and j["zeno_completions"][0]["t"] == z["t"]


def test_a_reference_written_as_csv_is_read_back_and_polished():
    """to_csv, then polish: the re-simulation under the sampled input finds the same events."""
    ref = saltus.references.example3()
    out = saltus.polish(ref.scene, ref.to_csv(0.001), ref.options)
    assert out["imported_events"] == 2 and out["simulated_events"] == 2
    np.testing.assert_allclose(out["trajectory"].event_times, ref.event_times, atol=1e-9)
    assert out["state_distance"] < 1e-9  # the input is piecewise linear: its samples interpolate it exactly
    with pytest.raises(saltus.InvalidArgument, match="no column 'v0'"):
        saltus.polish(ref.scene, "t,segment,mode,q0\n0,0,\"table:open\",x\n")


def _round_trip_cases():
    box = saltus.PlankBox()
    spatial = saltus.SpatialBox()
    x0 = np.zeros(12)
    x0[2] = 0.5 * spatial.size[2] + 0.1
    x0[6:8] = [2.0, 1.0]  # lands on four corners, slides diagonally: slip directions (dx, dy)
    completing = tight()
    completing.zeno_completion = True
    return {
        "ball (zeno)": lambda: saltus.simulate(saltus.BouncingBall(), [1.0, 0.0], 0.0, 5.0, options=tight()),
        "ball (completed)": lambda: saltus.simulate(saltus.BouncingBall(), [1.0, 0.0], 0.0, 5.0, options=completing),
        "example 3": saltus.references.example3,
        "point mass with friction": saltus.references.point_mass_with_friction,
        "plank-box flat landing": lambda: saltus.simulate(box, box.flat_state(), 0.0, 0.3, input=box.lowering_input(),
                                                          options=tight()),
        "hopper push-off": saltus.references.hopper_push_off,
        "spatial box": lambda: saltus.simulate(spatial, x0, 0.0, 1.0, options=tight()),
    }


@pytest.mark.parametrize("case", list(_round_trip_cases()))
def test_a_trajectory_written_as_complete_json_is_read_back_exactly(case, tmp_path):
    """to_json(complete=True), then read_trajectory, from the text and from a file: every segment's
    times and states bit for bit, every event's fields, the dense output between the steps, the
    Zeno fields; written again, the same JSON."""
    traj = _round_trip_cases()[case]()
    text = traj.to_json(complete=True)
    path = tmp_path / "trajectory.json"
    path.write_text(text)
    for back in (saltus.read_trajectory(text, traj.scene), saltus.read_trajectory(path, traj.scene),
                 saltus.read_trajectory(str(path), traj.scene)):
        assert type(back) is type(traj) and back.name == "read from JSON"
        assert back.to_json(complete=True) == text and back.to_json() == traj.to_json()
        assert back.status == traj.status and len(back) == len(traj)
        for a, b in zip(traj.segments, back.segments):
            assert b.mode == a.mode and b.contact_modes == a.contact_modes and b.sliding_contact == a.sliding_contact
            assert b.t_begin == a.t_begin and b.t_end == a.t_end
            np.testing.assert_array_equal(b.times, a.times)
            np.testing.assert_array_equal(b.states, a.states)
            inside = 0.5 * (a.times[:-1] + a.times[1:])  # between the step points: the dense output
            np.testing.assert_array_equal(back.sample(inside), traj.sample(inside))
        assert len(back.events) == len(traj.events)
        for a, b in zip(traj.events, back.events):
            for field in ["t", "impact", "input_jump", "guards", "mode_before", "mode_after", "contact_modes_before",
                          "contact_modes_after"]:
                assert getattr(b, field) == getattr(a, field), field
            np.testing.assert_array_equal(b.x_minus, a.x_minus)
            np.testing.assert_array_equal(b.x_plus, a.x_plus)
        np.testing.assert_array_equal(back.final_state, traj.final_state)
        np.testing.assert_array_equal(back.event_times, traj.event_times)
        for name in ["zeno_time", "zeno_time_uncertainty", "zeno_time_extrapolation_uncertainty",
                     "zeno_time_integration_uncertainty"]:
            a, b = getattr(traj, name), getattr(back, name)
            assert a == b or (math.isnan(a) and math.isnan(b)), name
        assert back.zeno_completions == traj.zeno_completions
        assert back.statistics == traj.statistics
        assert back.options.breakpoints == traj.options.breakpoints or not traj.options.breakpoints
    if traj.scene.nu > 0:
        with pytest.raises(saltus.InvalidArgument, match="does not hold its input law"):
            back.inputs([traj.t_begin])
    else:
        assert back.inputs([traj.t_begin]).shape == (1, 0)


def test_read_trajectory_refuses_what_it_cannot_rebuild(ball_trajectory, tmp_path):
    ball = saltus.BouncingBall()
    with pytest.raises(saltus.InvalidArgument, match="not written complete"):
        saltus.read_trajectory(ball_trajectory.to_json(), ball)
    j = json.loads(ball_trajectory.to_json(complete=True))
    del j["events"][0]["x_minus"]
    with pytest.raises(saltus.InvalidArgument, match=r"events\[0\] has no 'x_minus'"):
        saltus.read_trajectory(json.dumps(j), ball)
    with pytest.raises(saltus.InvalidArgument, match="trajectory JSON: .*parse error"):
        saltus.read_trajectory("{ not json", ball)
    with pytest.raises(saltus.InvalidArgument, match=r"x_plus is not an array of 4 numbers"):
        saltus.read_trajectory(saltus.references.example3().to_json(complete=True).replace(
            '"x_plus":[', '"x_plus":[0.5,'), saltus.PointMass())
    with pytest.raises(saltus.InvalidArgument, match=r"segments\[0\]\.pieces\[0\]\.c\[0\] is not an array of 4 numbers"):
        saltus.read_trajectory(ball_trajectory.to_json(complete=True), saltus.PointMass())  # another scene's
    with pytest.raises(TypeError):
        saltus.read_trajectory(ball_trajectory.to_json(complete=True), "ball")
    with pytest.raises(FileNotFoundError):
        saltus.read_trajectory(tmp_path / "missing.json", ball)
    with pytest.raises(TypeError, match="source must be JSON text or a path"):
        saltus.read_trajectory(3, ball)
