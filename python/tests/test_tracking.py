"""Tracking designs, the stability check and the Monte Carlo batch from Python (the point mass of
Example 3, as examples/tracking_stability.cpp's first case), and the chunked batch that
saltus.distributed runs: chunks merged equal one call over the whole batch, run for run."""
import pickle

import numpy as np
import pytest

import saltus


@pytest.fixture(scope="module")
def example3():
    ref = saltus.references.example3()
    lin = saltus.linearise(ref, spreading=0.1)
    return ref, lin


@pytest.fixture(scope="module")
def lqr(example3):
    ref, lin = example3
    gains = saltus.lqr_design(lin, Q=np.eye(4), R=0.1 * np.eye(2), Q_final=np.eye(4))
    return saltus.tracking(lin, gains)


def test_lqr_is_stable_and_open_loop_replay_is_not(example3, lqr):
    ref, lin = example3
    report = lqr.check_stability()
    assert report.verdict == "stable"
    assert report.lower_bound <= report.upper_bound < 1.0
    assert report.t_final == pytest.approx(ref.t_end)
    replay = saltus.tracking(lin, saltus.constant_gains(lin, np.zeros((2, 4)))).check_stability()
    assert replay.verdict != "stable"
    assert replay.upper_bound > 1.0


def test_monte_carlo_agrees_with_the_check(lqr):
    report = lqr.check_stability()
    mc = lqr.monte_carlo(runs=24, threads=1)
    assert mc.runs == 24 and mc.failed == 0 and mc.kept_event_sequence == 24
    assert mc.shrank == 24
    assert mc.departures == []  # every run kept the events: none left them
    assert mc.observed_rate_max <= report.upper_rate + 1e-3
    # the first-order regime: observed and predicted amplifications agree within 5 %
    assert mc.max_log_discrepancy < 0.05
    assert mc.observed.shape == (24,) and mc.predicted.shape == (24,)


def test_a_batch_without_kept_runs_reports_no_statistic_of_them():
    """The hop starts on the table: perturbations of its gap put the mass inside it, and every run
    fails. The statistics of the kept runs are then NaN, never a 0 that reads as a rate, and so are
    the failed runs' amplifications; chunks merged say the same."""
    lin = saltus.linearise(saltus.references.point_mass_hop())
    tracker = saltus.tracking(lin, saltus.lqr_design(lin, R=0.1 * np.eye(2)))
    mc = tracker.monte_carlo(runs=6, threads=1)
    assert mc.failed == 6 and mc.kept_event_sequence == 0
    for name in ["observed_rate_max", "observed_rate_median", "max_log_discrepancy"]:
        assert np.isnan(getattr(mc, name)), name
    assert np.isnan(mc.observed).all()
    merged = saltus.MonteCarloReport.merge([tracker.monte_carlo(runs=6, first=f, count=3, threads=1) for f in (0, 3)])
    assert np.isnan(merged.observed_rate_median) and np.isnan(merged.max_log_discrepancy)


def test_chunks_merge_into_the_whole_batch(lqr):
    whole = lqr.monte_carlo(runs=20, threads=1)
    parts = [lqr.monte_carlo(runs=20, first=f, count=c, threads=1) for f, c in [(12, 8), (0, 5), (5, 7)]]
    merged = saltus.MonteCarloReport.merge(parts)
    np.testing.assert_array_equal(merged.observed, whole.observed)
    np.testing.assert_array_equal(merged.predicted, whole.predicted)
    for name in ["runs", "failed", "kept_event_sequence", "observed_rate_max", "observed_rate_median",
                 "predicted_rate_max", "max_log_discrepancy", "grew", "shrank", "failure_reasons", "departures",
                 "relative_to_nominal_run", "nominal_run_deviation", "nominal_run_max_deviation",
                 "nominal_run_departure"]:
        assert getattr(merged, name) == getattr(whole, name), name
    # every run measured against the nominal run, whose error against the simulated reference is tiny
    assert whole.relative_to_nominal_run and whole.nominal_run_departure == ""
    assert 0.0 <= whole.nominal_run_deviation <= whole.nominal_run_max_deviation < 1e-8
    # a chunk runs the batch's own perturbations, not a fresh draw
    assert parts[1].observed[0] == whole.observed[0] and parts[0].observed[0] == whole.observed[12]


def test_merge_refuses_gaps_and_pickles_roundtrip(lqr):
    a = lqr.monte_carlo(runs=10, first=0, count=3, threads=1)
    c = lqr.monte_carlo(runs=10, first=5, count=2, threads=1)
    with pytest.raises(saltus.InvalidArgument, match="do not follow"):
        saltus.MonteCarloReport.merge([a, c])
    back = pickle.loads(pickle.dumps(a))
    np.testing.assert_array_equal(back.observed, a.observed)
    assert (back.first, back.batch_runs, back.observed_rate_max) == (0, 10, a.observed_rate_max)
    assert (back.relative_to_nominal_run, back.nominal_run_deviation, back.nominal_run_departure) == \
        (a.relative_to_nominal_run, a.nominal_run_deviation, a.nominal_run_departure)
    r = lqr.check_stability()
    assert pickle.loads(pickle.dumps(r)).upper_bound == r.upper_bound


def test_bad_tracking_input_raises(example3, lqr):
    ref, lin = example3
    with pytest.raises(saltus.InvalidArgument, match=r"expected \(nu, nx\) = \(2, 4\)"):
        saltus.constant_gains(lin, np.zeros((4, 2)))
    with pytest.raises(saltus.InvalidArgument, match=r"R has shape"):
        saltus.lqr_design(lin, R=np.eye(3))
    with pytest.raises(saltus.InvalidArgument, match="runs must be >= 1"):
        lqr.monte_carlo(runs=0)
    with pytest.raises(saltus.InvalidArgument, match="size must be > 0"):
        lqr.monte_carlo(runs=2, size=-1.0)
    with pytest.raises(saltus.InvalidArgument, match="not a non-empty part"):
        lqr.monte_carlo(runs=5, first=4, count=3)


def test_periodic_hop_pd(example3):
    ref = saltus.references.point_mass_hop(3.2)
    lin = saltus.linearise(ref, spreading=0.1)
    stable = saltus.tracking(lin, saltus.constant_gains(lin, saltus.pd_gain(10 * np.eye(2), 4 * np.eye(2))))
    unstable = saltus.tracking(lin, saltus.constant_gains(lin, saltus.pd_gain(10 * np.eye(2), -1 * np.eye(2))))
    assert stable.check_periodic_stability(1.0).verdict == "stable"
    assert unstable.check_periodic_stability(1.0).verdict == "unstable"


def test_a_reference_under_a_python_input_law_gives_the_same_design(example3):
    """Example 3's input written in Python: the linearisation, the check and a Monte Carlo batch on
    two C++ threads (each calling the Python law under the GIL) agree with the C++ law's."""
    ref, lin = example3
    options = ref.options
    options.breakpoints = [1.0]
    law = lambda t, x: np.array([7.0, 0.0 if t < 1.0 else 2.0 * 9.81 * (t - 1.0)])  # noqa: E731
    py_ref = saltus.simulate(ref.scene, [0.0, 1.0, 0.0, 0.0], 0.0, 2.0, input=law, options=options)
    py_lin = saltus.linearise(py_ref, spreading=0.1)
    designs = [saltus.tracking(l, saltus.lqr_design(l, R=0.1 * np.eye(2))) for l in (lin, py_lin)]
    checks = [d.check_stability() for d in designs]
    assert checks[1].upper_bound == pytest.approx(checks[0].upper_bound, rel=1e-8)
    batches = [d.monte_carlo(runs=6, threads=2) for d in designs]
    assert batches[1].failed == 0 and batches[1].threads == 2
    np.testing.assert_allclose(batches[1].observed, batches[0].observed, rtol=1e-6)


def test_analyse_reference_is_the_step_by_step_analysis(example3, lqr):
    """analyse_reference in one call on Example 3 (LQR Q = I, R = 0.1 I, Q_final = I, spreading 0.1 s)
    gives what the bindings give step by step on the same reference: the events' |G_z|_2 of
    jump_gains, the check's verdict and bounds, the Monte Carlo batch run for run (the same seed and
    perturbations), and the design's gains."""
    ref, lin = example3
    lines = []
    a = saltus.analyse_reference(ref, Q=np.eye(4), R=0.1 * np.eye(2), Q_final=np.eye(4), spreading=0.1, runs=24,
                                 threads=1, design_name="LQR R = 0.1 I", progress=lines.append)
    assert a["completed"] and "failed_at" not in a
    assert a["design"] == "LQR R = 0.1 I"
    gains = saltus.jump_gains(ref, feedback="signal")
    assert [e["t"] for e in a["events"]] == list(ref.event_times)
    assert [e["conewise"] for e in a["events"]] == [False, False]
    for row, g in zip(a["events"], gains):
        assert row["saltation_norm"] == pytest.approx(np.linalg.norm(g.G_z, 2), rel=1e-12)
    check = lqr.check_stability()
    assert a["verdict"] == check.verdict == "stable"
    assert a["upper_bound"] == pytest.approx(check.upper_bound, rel=1e-12)
    assert a["lower_bound"] == pytest.approx(check.lower_bound, rel=1e-12)
    assert a["predicted_rate"] == pytest.approx(check.upper_rate, rel=1e-12)
    batch = lqr.monte_carlo(runs=24, threads=1)
    mc = a["monte_carlo"]
    assert mc["runs"] == 24 and mc["failed"] == 0 and mc["kept_event_sequence"] == batch.kept_event_sequence == 24
    assert mc["shrank"] == batch.shrank and mc["grew"] == batch.grew == 0
    assert mc["observed_rate_max"] == pytest.approx(batch.observed_rate_max, rel=1e-12)
    assert mc["max_log_discrepancy"] == pytest.approx(batch.max_log_discrepancy, rel=1e-9)
    np.testing.assert_allclose(mc["amplifications"]["observed"], batch.observed, rtol=1e-12)
    assert a["agree"] is True
    step_gains = saltus.lqr_design(lin, Q=np.eye(4), R=0.1 * np.eye(2), Q_final=np.eye(4))
    for segment, t in [(0, 0.2), (1, 1.0), (2, 1.8)]:
        np.testing.assert_allclose(a["gains"].gain(segment, t), step_gains.gain(segment, t), rtol=1e-12, atol=1e-14)
    assert lines[0].startswith("analysis: 2 events linearised")
    assert any(line.startswith("analysis: stable, a(T) in [") for line in lines), lines


def test_analyse_reference_of_a_python_simulation_and_of_a_failing_design(example3):
    """A reference simulated from Python under a Python input law is analysed as the C++ law's (the
    batch on two threads, each calling the law under the GIL); a design the library refuses (R not
    positive definite) ends the analysis at its stage, the jump gains before it kept."""
    ref, _ = example3
    options = ref.options
    options.breakpoints = [1.0]
    law = lambda t, x: np.array([7.0, 0.0 if t < 1.0 else 2.0 * 9.81 * (t - 1.0)])  # noqa: E731
    py_ref = saltus.simulate(ref.scene, [0.0, 1.0, 0.0, 0.0], 0.0, 2.0, input=law, options=options)
    a, b = (saltus.analyse_reference(r, R=0.1 * np.eye(2), spreading=0.1, runs=6, threads=2, progress=lambda s: None)
            for r in (ref, py_ref))
    assert b["completed"] and b["verdict"] == a["verdict"] == "stable"
    assert b["upper_bound"] == pytest.approx(a["upper_bound"], rel=1e-8)
    assert b["monte_carlo"]["threads"] == 2 and b["monte_carlo"]["failed"] == 0
    np.testing.assert_allclose(b["monte_carlo"]["amplifications"]["observed"],
                               a["monte_carlo"]["amplifications"]["observed"], rtol=1e-6)
    failed = saltus.analyse_reference(ref, R=-np.eye(2), runs=2, progress=lambda s: None)
    assert not failed["completed"]
    assert failed["failed_at"] == "tracking design" and "R" in failed["failure"]
    assert len(failed["events"]) == 2 and "verdict" not in failed and "gains" not in failed


def test_analyse_reference_perturbs_inside_the_initial_subspace():
    """The periodic hop starts on the table: a batch that perturbs every coordinate puts the mass
    inside it and every run fails; with the initial subspace of the horizontal position and
    velocity (the gap and its rate left at zero) every run completes, and the check bounds the same
    subspace."""
    hop = saltus.references.point_mass_hop()
    everywhere = saltus.analyse_reference(hop, R=0.1 * np.eye(2), runs=4, threads=1, progress=lambda s: None)
    assert everywhere["monte_carlo"]["failed"] == 4
    E = np.zeros((4, 2))
    E[0, 0] = E[2, 1] = 1.0
    inside = saltus.analyse_reference(hop, R=0.1 * np.eye(2), initial_subspace=E, runs=4, threads=1,
                                      progress=lambda s: None)
    assert inside["completed"] and inside["monte_carlo"]["failed"] == 0
    assert inside["monte_carlo"]["kept_event_sequence"] == 4
    assert inside["upper_bound"] <= everywhere["upper_bound"] * (1 + 1e-12)  # a bound over a subset
