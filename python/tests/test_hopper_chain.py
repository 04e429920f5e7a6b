"""The hopper's optimise-then-analyse chain from Python on the one-hole bed (HopperOverOneHole: from
rest at x = 0 to (1, 0.4, 0, 0) in T = 1 s over the first hole), the C++ run_hopper_chain that
`hopper --json` runs over three holes: discovery by the hole continuation and the time-freezing
homotopy, the footsteps' mode-schedule refinement, then analyse_reference (LQR R = I, 30 Monte
Carlo runs at eps = 1e-6). About a minute on one core. Checked as
HopperOverOneHole.WholeChainDiscoveryRefinementAnalysis checks it in C++: exact modes, the
per-phase re-simulation within 1e-6, a stable design the batch agrees with, and a gait that any
solution must have (every touchdown outside the hole, one flight across it, no lift-off last)."""
import numpy as np
import pytest

import saltus

HOLE_CENTRE, HOLE_HALF_WIDTH = 0.5, 0.25  # scenes/hopper_holes.hpp


@pytest.fixture(scope="module")
def chain():
    lines = []
    result = saltus.optimal_control.hopper_over_one_hole(progress=lines.append)
    return result, lines


def test_the_chain_refines_an_exact_reference(chain):
    r, _ = chain
    assert r["task"] == "one hole" and r["initialisation"] == "paper"
    assert r["converged"] is True and r["stage"] == "refined", r["stage"]
    assert r["mode_validity_violation"] <= 1e-9
    assert r["phase_resim_max_error"] <= 1e-6
    assert r["max_path_violation"] <= 1e-6 and r["target_error"] <= 1e-6
    assert r["discovery"]["settled"] in (True, False) and len(r["discovery"]["steps"]) >= 1
    assert len(r["footholds"]) >= 2 and r["footholds"][-1] == 1.0
    assert r["refinement"]["stage"] == "refined"
    assert r["solve_seconds"] == pytest.approx(r["discovery_seconds"] + r["refinement_seconds"])
    assert r["event_times"] == r["events"] and len(r["event_times"]) >= 2


def test_the_refined_reference_has_the_gait_over_the_hole(chain):
    r, _ = chain
    ref = r["reference"]
    assert isinstance(ref, saltus._saltus.HopperTrajectory)
    np.testing.assert_array_equal(ref.event_times, r["event_times"])
    assert ref.t_end == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(ref.final_state[:4], [1.0, 0.4, 0.0, 0.0], atol=1e-6)
    hopper = ref.scene
    last_lift_off, crossings = np.nan, 0
    for ev in ref.events:
        assert len(ev.guards) == 1
        kind = ev.guards[0][2]
        foot_x = hopper.foot(ev.x_minus[:4])[0]
        if kind == "release":
            last_lift_off = foot_x
        if kind != "touchdown":
            continue
        assert abs(foot_x - HOLE_CENTRE) >= HOLE_HALF_WIDTH - 1e-6  # lands on the ground, outside the hole
        if last_lift_off <= HOLE_CENTRE - HOLE_HALF_WIDTH + 1e-6 and foot_x >= HOLE_CENTRE + HOLE_HALF_WIDTH - 1e-6:
            crossings += 1
    assert crossings == 1
    assert ref.events[-1].guards[0][2] != "release"


def test_the_analysis_is_stable_and_the_monte_carlo_batch_agrees(chain):
    r, _ = chain
    a = r["analysis"]
    assert a["verdict"] == "stable" and a["upper_bound"] < 1.0
    assert len(a["events"]) == len(r["event_times"])
    mc = a["monte_carlo"]
    assert mc["runs"] == 30 and mc["perturbation_size"] == 1e-6
    assert mc["kept_event_sequence"] >= 10 and mc["grew"] == 0
    assert mc["max_log_discrepancy"] <= 0.05
    assert a["agree"] is True
    # hopper --json's keys: the batch's size and kept runs beside the verdict too.
    assert a["runs"] == mc["runs"] and a["kept_event_sequence"] == mc["kept_event_sequence"]
    # The reference is analysed again from Python: its jump gains are the analysis's.
    gains = saltus.jump_gains(r["reference"], feedback="signal")
    for row, g in zip(a["events"], gains):
        assert row["saltation_norm"] == pytest.approx(np.linalg.norm(g.G_z, 2), rel=1e-9)


def test_progress_lines_of_every_stage_reach_the_callable(chain):
    _, lines = chain
    assert all(isinstance(line, str) and "\n" not in line for line in lines)
    assert any(line.startswith("refinement:") for line in lines)
    assert any(line.startswith("analysis:") for line in lines)


def test_the_chains_refuse_bad_arguments_before_solving():
    with pytest.raises(saltus.InvalidArgument, match="runs must be >= 1"):
        saltus.optimal_control.hopper_over_one_hole(runs=0)
    with pytest.raises(saltus.InvalidArgument, match="deviation_times"):
        saltus.optimal_control.hopper_over_one_hole(deviation_times=-1)
    with pytest.raises(saltus.InvalidArgument, match="initialisation must be 'paper' or 'hop_guess'"):
        saltus.optimal_control.hopper_over_three_holes(initialisation="hops")
    with pytest.raises(saltus.InvalidArgument, match="callable"):
        saltus.optimal_control.hopper_over_three_holes(progress=3)
