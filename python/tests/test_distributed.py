"""saltus.distributed on a LocalCluster of two worker processes: the chunked Monte Carlo batch and
the sweep of PD gains equal their single-process results; a worker's saltus exception reaches the
client with its type."""
import distributed as dask_distributed  # Debian: python3-distributed (.ci/install-deps.sh)
import numpy as np
import pytest

import saltus
from saltus import distributed


@pytest.fixture(scope="module")
def client():
    with dask_distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                       silence_logs=40) as cluster, dask_distributed.Client(cluster) as c:
        yield c


def test_chunks_cover_the_batch():
    assert distributed.chunks(10, 4) == [(0, 4), (4, 4), (8, 2)]
    with pytest.raises(saltus.InvalidArgument):
        distributed.chunks(0, 4)


def test_monte_carlo_on_two_workers_equals_one_process(client):
    case = distributed.TrackingCase()  # Example 3, LQR Q = I, R = 0.1 I
    local = case.build().monte_carlo(runs=30, threads=1)
    remote = distributed.monte_carlo(client, case, runs=30, chunk=7)
    assert remote.runs == 30
    np.testing.assert_array_equal(remote.observed, local.observed)
    np.testing.assert_array_equal(remote.predicted, local.predicted)
    for name in ["failed", "kept_event_sequence", "observed_rate_max", "observed_rate_median", "predicted_rate_max",
                 "max_log_discrepancy", "grew", "shrank", "departures"]:
        assert getattr(remote, name) == getattr(local, name), name
    # both worker processes took part: each built the case (its per-process cache) to run a chunk
    built = client.run(lambda: __import__("saltus.distributed").distributed._build.cache_info().currsize)
    assert len(built) == 2 and all(n >= 1 for n in built.values())


def test_stability_sweep_equals_one_process(client):
    cases = distributed.pd_grid([5.0, 40.0], [-1.0, 4.0])
    remote = distributed.stability_sweep(client, cases)
    local = [c.build().check_stability() for c in cases]
    assert [r.verdict for r in remote] == [r.verdict for r in local]
    assert [r.upper_bound for r in remote] == [r.upper_bound for r in local]
    assert "stable" in [r.verdict for r in remote] and len(set(r.verdict for r in remote)) > 1


def test_a_worker_exception_keeps_its_type(client):
    with pytest.raises(saltus.InvalidArgument, match="size must be > 0"):
        distributed.monte_carlo(client, distributed.TrackingCase(), runs=4, chunk=2, size=-1.0)
