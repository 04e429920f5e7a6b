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
