"""The stability check of tracking designs and their Monte Carlo validation on a Dask cluster.

The reference is the guiding example's Example 3 (impact, sliding, lift-off); the designs are a
time-varying LQR (Q = I, R = 0.1 I) and a grid of PD gains. The Monte Carlo batch is split into
chunks of runs, one task each; the merged report equals the single-process one run for run. The
script prints the check, the batch in one process and on 1 and 2 worker processes (runs per
second), and the verdicts over the PD grid.

    PYTHONPATH=<build>/python OPENBLAS_NUM_THREADS=1 /usr/bin/python3 examples/python/stability_dask.py \
        [--runs 200] [--chunk 25] [--scheduler tcp://host:8786]

Without --scheduler it starts a LocalCluster of worker processes on this machine; with it, it uses
the cluster of `dask scheduler` and `dask worker tcp://host:8786 --nthreads 1` started by hand
(docs/python.md).
"""
import argparse
import sys
import time

import numpy as np
from dask.distributed import Client, LocalCluster

import saltus
from saltus import distributed


def timed(f):
    t = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=200)
    parser.add_argument("--chunk", type=int, default=25)
    parser.add_argument("--scheduler", default=None, help="address of a running dask scheduler")
    parser.add_argument("--workers", type=int, nargs="*", default=[1, 2], help="LocalCluster sizes to time")
    args = parser.parse_args()

    case = distributed.TrackingCase()  # Example 3, LQR Q = I, R = 0.1 I
    design, build_seconds = timed(case.build)
    check = design.check_stability()
    print(f"Example 3, LQR (Q = I, R = 0.1 I): {check.verdict}, a(T) in [{check.lower_bound:.4g}, "
          f"{check.upper_bound:.4g}], rate {check.upper_rate:.3g} 1/s (design built in {build_seconds:.2f} s)")

    local, local_seconds = timed(lambda: design.monte_carlo(runs=args.runs, threads=1))
    print(f"Monte Carlo, {args.runs} runs in this process (one thread): {local_seconds:.2f} s, "
          f"{args.runs / local_seconds:.1f} runs/s; kept {local.kept_event_sequence}, failed {local.failed}, "
          f"observed rate max {local.observed_rate_max:.3g} 1/s")

    def on(client, label):
        client.run(lambda: None)  # workers up
        distributed.monte_carlo(client, case, runs=2 * len(client.scheduler_info()["workers"]), chunk=1)  # warm: build the case
        report, seconds = timed(lambda: distributed.monte_carlo(client, case, runs=args.runs, chunk=args.chunk))
        same = np.array_equal(report.observed, local.observed) and report.observed_rate_max == local.observed_rate_max
        print(f"Monte Carlo on {label}: {seconds:.2f} s, {args.runs / seconds:.1f} runs/s, speed-up "
              f"{local_seconds / seconds:.2f} against one process; equal to the single-process report: {same}")
        return same

    ok = True
    if args.scheduler:
        with Client(args.scheduler) as client:
            ok = on(client, f"the cluster at {args.scheduler}") and ok
            sweep_client = client
            verdicts = distributed.stability_sweep(sweep_client, distributed.pd_grid([5, 20, 80], [-1, 1, 4]))
    else:
        verdicts = None
        for n in args.workers:
            with LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                              silence_logs=40) as cluster, Client(cluster) as client:
                ok = on(client, f"{n} local worker process{'es' if n > 1 else ''}") and ok
                if verdicts is None:
                    verdicts = distributed.stability_sweep(client, distributed.pd_grid([5, 20, 80], [-1, 1, 4]))
    print("PD sweep on Example 3 (kp [N/m], kd [N s/m]): verdict, upper bound of a(T)")
    for c, r in zip(distributed.pd_grid([5, 20, 80], [-1, 1, 4]), verdicts):
        print(f"  kp = {c.kp:5.1f}, kd = {c.kd:5.1f}: {r.verdict:10s} {r.upper_bound:.4g}")
    return 0 if ok and check.verdict == "stable" else 1


if __name__ == "__main__":
    sys.exit(main())
