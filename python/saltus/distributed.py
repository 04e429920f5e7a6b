"""Monte Carlo batches and sweeps of tracking designs as tasks on a Dask cluster.

A batch is split into chunks of consecutive runs; every chunk is a task that a worker runs with
``Tracking.monte_carlo(runs=..., first=..., count=..., threads=1)``, drawing the same perturbations
as one call over the whole batch would (one random stream from the seed), so the merged report
(``MonteCarloReport.merge``) equals the single-process one run for run. A sweep (for example the
stability verdict over a grid of PD gains) is one task per design.

What travels to the workers is a ``TrackingCase``: a small, hashable description of the reference
and the design, built in the worker (the reference's simulation, its linearisation and the LQR
design take a fraction of a second to seconds) and kept there for the next task of the same case
(``_build`` caches it per worker process).

Use it with any ``dask.distributed.Client``::

    from dask.distributed import Client, LocalCluster
    from saltus import distributed
    with LocalCluster(n_workers=2, processes=True, threads_per_worker=1) as cluster, Client(cluster) as client:
        report = distributed.monte_carlo(client, distributed.TrackingCase(), runs=200, chunk=25)

On several machines: start ``dask scheduler`` on one, ``dask worker tcp://<scheduler>:8786
--nworkers 2 --nthreads 1`` on each (with ``saltus`` importable there), and give the client
``Client("tcp://<scheduler>:8786")``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Iterable, Sequence

import numpy as np

import saltus


@dataclass(frozen=True)
class TrackingCase:
    """A tracking design on one of the scene library's references (``saltus.references``).

    reference
        the name of a function of ``saltus.references`` (``"example3"``, ``"point_mass_hop"``,
        ``"point_mass_with_friction"``, ``"plank_box"``) and ``reference_args`` its arguments.
    spreading
        s: how far each reference segment is extended past its events (reference spreading).
    design
        ``"lqr"``: time-varying LQR with Q = diag(q) (or q I), R = diag(r) (or r I),
        Q_final = Q; ``"pd"``: K = -[kp I, kd I] (nu = nq scenes: the point mass), kp in N/m,
        kd in N s/m; ``"gain"``: the constant gain ``K`` (nu x nx, nested tuples) on every
        segment.
    """

    reference: str = "example3"
    reference_args: tuple = ()
    spreading: float = 0.1
    design: str = "lqr"
    q: float | tuple = 1.0
    r: float | tuple = 0.1
    kp: float = 10.0
    kd: float = 4.0
    K: tuple = field(default=())

    def build(self):
        """The ``Tracking`` object (controller and closed-loop linearisation) of this case."""
        make = getattr(saltus.references, self.reference, None)
        if make is None:
            raise saltus.InvalidArgument(f"TrackingCase: no reference '{self.reference}' in saltus.references")
        ref = make(*self.reference_args)
        lin = saltus.linearise(ref, spreading=self.spreading, feedback="signal")
        scene = ref.scene
        nx, nu = scene.nx, scene.nu
        if self.design == "lqr":
            Q = np.diag(np.broadcast_to(np.asarray(self.q, dtype=float), (nx,)))
            R = np.diag(np.broadcast_to(np.asarray(self.r, dtype=float), (nu,)))
            gains = saltus.lqr_design(lin, Q=Q, R=R, Q_final=Q)
        elif self.design == "pd":
            if nu != scene.nq:
                raise saltus.InvalidArgument(f"TrackingCase: design 'pd' needs nu = nq, the scene has nu = {nu}, "
                                             f"nq = {scene.nq}: give K (design 'gain')")
            eye = np.eye(nu)
            gains = saltus.constant_gains(lin, saltus.pd_gain(self.kp * eye, self.kd * eye))
        elif self.design == "gain":
            gains = saltus.constant_gains(lin, np.asarray(self.K, dtype=float))
        else:
            raise saltus.InvalidArgument(f"TrackingCase: design must be 'lqr', 'pd' or 'gain', got '{self.design}'")
        return saltus.tracking(lin, gains)


@functools.lru_cache(maxsize=16)
def _build(case: TrackingCase):
    """The case's Tracking object, built once per (worker) process."""
    return case.build()


def _monte_carlo_chunk(case: TrackingCase, runs: int, first: int, count: int, options: dict):
    return _build(case).monte_carlo(runs=runs, first=first, count=count, threads=1, **options)


def _check_stability(case: TrackingCase, options: dict):
    return _build(case).check_stability(**options)


def chunks(runs: int, chunk: int) -> list[tuple[int, int]]:
    """[(first, count), ...] covering [0, runs) in consecutive pieces of at most ``chunk`` runs."""
    if runs < 1 or chunk < 1:
        raise saltus.InvalidArgument(f"chunks: runs and chunk must be >= 1, got {runs} and {chunk}")
    return [(first, min(chunk, runs - first)) for first in range(0, runs, chunk)]


def monte_carlo(client, case: TrackingCase, runs: int = 200, chunk: int = 25, **options) -> saltus.MonteCarloReport:
    """The Monte Carlo batch of ``case`` as tasks of ``chunk`` runs on ``client``'s workers.

    ``options`` are those of ``Tracking.monte_carlo`` (size, scale, seed, t_final, weight,
    output_weight). Returns the merged report: equal, run for run, to
    ``case.build().monte_carlo(runs=runs, **options)`` in one process. ``seconds`` of the merged
    report is the sum of the chunks' simulation times (the wall time is the caller's to measure).
    A chunk's exception (``saltus.InvalidArgument`` for bad options, ...) is raised here.
    """
    pieces = chunks(runs, chunk)
    futures = [client.submit(_monte_carlo_chunk, case, runs, first, count, options, pure=False)
               for first, count in pieces]
    return saltus.MonteCarloReport.merge(client.gather(futures))


def stability_sweep(client, cases: Sequence[TrackingCase], **options) -> list[saltus.StabilityReport]:
    """``check_stability(**options)`` of every case, one task each, in the order given."""
    futures = [client.submit(_check_stability, case, options, pure=False) for case in cases]
    return client.gather(futures)


def pd_grid(kps: Iterable[float], kds: Iterable[float], base: TrackingCase = TrackingCase()) -> list[TrackingCase]:
    """The cases of ``base`` with design 'pd' over the grid kps x kds (kp-major order)."""
    from dataclasses import replace
    return [replace(base, design="pd", kp=float(kp), kd=float(kd)) for kp in kps for kd in kds]
