"""The optimise-then-analyse pipeline from Python: the point mass to the target by time-freezing
discovery and the mode-schedule refinement (the README's figures: refined objective 18.7116, mode
validity ~1e-22), its progress lines in Python, and the refined reference analysed by the
bindings (jump gains, an LQR design and its stability check)."""
import json
import logging

import numpy as np
import pytest

import saltus


@pytest.fixture(scope="module")
def solved():
    lines = []
    result = saltus.optimal_control.point_mass_to_the_target(progress=lines.append)
    return result, lines


def test_the_refined_reference_is_the_documented_optimum(solved):
    r, _ = solved
    assert r["stage"] == "refined" and r["converged"]
    assert r["objective"] == pytest.approx(18.7116, abs=1e-4)
    assert r["objective"] < r["relaxed_objective"]
    assert r["mode_validity_violation"] < 1e-12
    assert r["phase_resim_max_error"] < 1e-8
    assert r["schedule"] == "table:open [touchdown table] table:slip+"
    assert json.loads(r["refinement_json"])["stage"] == "refined"


def test_progress_lines_reach_the_callable(solved):
    _, lines = solved
    assert len(lines) >= 3
    assert all(isinstance(line, str) and "\n" not in line for line in lines)
    assert lines[0].startswith("mpcc step")
    assert any(line.startswith("refinement:") for line in lines)


def test_the_refined_reference_is_analysed_in_python(solved):
    r, _ = solved
    ref = r["reference"]
    assert isinstance(ref, saltus._saltus.PointMassTrajectory)
    assert [e.t for e in ref.events] == pytest.approx(r["event_times"])
    assert ref.events[0].guards == [(0, "table", "touchdown")]
    np.testing.assert_allclose(ref.sample([2.0])[0], [3.0, 0.0, 0.0, 0.0], atol=1e-8)  # at rest at x = 3
    gain = saltus.jump_gains(ref, feedback="signal")[0]
    assert gain.G_z.shape == (4, 4) and gain.G_z[3, 3] == pytest.approx(0.0, abs=1e-12)  # inelastic landing
    lin = saltus.linearise(ref, spreading=0.05)
    report = saltus.tracking(lin, saltus.lqr_design(lin, R=0.1 * np.eye(2))).check_stability()
    assert report.verdict == "stable"


def test_progress_goes_to_the_logger_by_default_and_a_failing_sink_raises(caplog):
    with caplog.at_level(logging.INFO, logger="saltus"):
        saltus.optimal_control.point_mass_to_the_target()
    assert any(rec.name == "saltus" and rec.getMessage().startswith("mpcc step") for rec in caplog.records)

    def sink(line):
        raise KeyError("the sink failed")

    with pytest.raises(KeyError, match="the sink failed"):
        saltus.optimal_control.point_mass_to_the_target(progress=sink)
    with pytest.raises(saltus.InvalidArgument, match="progress must be a callable"):
        saltus.optimal_control.point_mass_to_the_target(progress=3)


def test_the_plank_box_pipeline_refuses_bad_arguments_before_solving():
    # Each refusal comes before the two-minute solve (plank_box_flat_landing's docstring).
    with pytest.raises(saltus.InvalidArgument, match="max_edits"):
        saltus.optimal_control.plank_box_flat_landing(max_edits=-1)
    with pytest.raises(saltus.InvalidArgument, match="runs"):
        saltus.optimal_control.plank_box_flat_landing(runs=0)
    with pytest.raises(saltus.InvalidArgument, match="callable"):
        saltus.optimal_control.plank_box_flat_landing(progress=3)
