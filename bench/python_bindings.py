"""What the Python bindings cost, and what Dask gives on this machine.

  1. simulate(): the bouncing ball (e_n = 0.5, 1 m, 1 s: 2 impacts) called from Python against the
     simulator's own wall time measured in C++ (Trajectory.statistics["wall_seconds"]): the
     difference is the binding's overhead per call (argument conversion, the copy of the scene,
     the trajectory's hand-over).
  2. jump_gains(): one call on a trajectory with 1 event and on one with 14 (the ball until its
     Zeno time): the slope is the C++ cost of one gain, the intercept the overhead per call.
  3. An input law written in Python: the point mass with friction under a constant thrust, the
     C++ constant law against a Python callable u(t, x) returning the same u; the difference per
     call of the law.
  4. The Monte Carlo batch of Example 3's LQR design (200 runs): one process on one thread, the
     C++ thread pool on 2 threads, and saltus.distributed on a LocalCluster of 1 and 2 worker
     processes (chunks of 25 runs). Wall times and runs per second; "compute" is the sum of the
     chunks' simulation times, so wall - compute / workers is Dask's overhead.

    PYTHONPATH=<build>/python OPENBLAS_NUM_THREADS=1 /usr/bin/python3 bench/python_bindings.py [--json]

Times are medians of repeated calls; compare the ratios of one run (docs/results.md's rule), and
read the load average printed first: another process on the machine halves what two workers give.
"""
import argparse
import json
import os
import statistics
import sys
import time

import numpy as np

import saltus
from saltus import distributed


def median_time(f, repeat):
    times = []
    out = None
    for _ in range(repeat):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def simulate_overhead(repeat):
    ball = saltus.BouncingBall()
    x0 = np.array([1.0, 0.0])
    walls, cpp = [], []
    for _ in range(repeat):
        t = time.perf_counter()
        traj = saltus.simulate(ball, x0, 0.0, 1.0)
        walls.append(time.perf_counter() - t)
        cpp.append(traj.statistics["wall_seconds"])
    py, c = statistics.median(walls), statistics.median(cpp)
    read, _ = median_time(lambda: (traj.segments, traj.events), repeat)
    return {"case": "bouncing ball, 1 m, 1 s", "events": len(traj.events), "python_seconds": py, "cpp_seconds": c,
            "overhead_seconds": py - c, "overhead_fraction": (py - c) / py, "read_segments_events_seconds": read}


def jump_gain_overhead(repeat):
    ball = saltus.BouncingBall()
    short = saltus.simulate(ball, [1.0, 0.0], 0.0, 0.6)
    long = saltus.simulate(ball, [1.0, 0.0], 0.0, 5.0)
    t1, _ = median_time(lambda: saltus.jump_gains(short), repeat)
    tn, _ = median_time(lambda: saltus.jump_gains(long), repeat)
    n1, nn = len(short.events), len(long.events)
    per_gain = (tn - t1) / (nn - n1)
    return {"events": [n1, nn], "seconds": [t1, tn], "cpp_seconds_per_gain": per_gain,
            "overhead_seconds_per_call": t1 - n1 * per_gain}


def python_input_law_cost(repeat):
    scene = saltus.PointMass(friction="planar", mu=0.5)
    x0 = [0.0, 0.3, 2.0, 0.0]
    u = np.array([1.0, 3.0])
    calls = [0]

    def law(t, x):
        calls[0] += 1
        return u

    tc, a = median_time(lambda: saltus.simulate(scene, x0, 0.0, 2.0, input=u), repeat)
    calls[0] = 0
    tp, b = median_time(lambda: saltus.simulate(scene, x0, 0.0, 2.0, input=law), repeat)
    per_run_calls = calls[0] / repeat
    assert np.array_equal(a.final_state, b.final_state)
    return {"case": "point mass with friction, constant thrust, 2 s", "cpp_law_seconds": tc,
            "python_law_seconds": tp, "ratio": tp / tc, "law_calls_per_run": per_run_calls,
            "seconds_per_python_call": (tp - tc) / per_run_calls}


def dask_batch(runs, chunk, repeat):
    from dask.distributed import Client, LocalCluster

    case = distributed.TrackingCase()  # Example 3, LQR Q = I, R = 0.1 I
    design = case.build()
    design.check_stability()  # the closed-loop transitions, computed once (as in every worker's first task)
    rows = []
    t1, ref = median_time(lambda: design.monte_carlo(runs=runs, threads=1), repeat)
    rows.append({"how": "one process, one thread", "seconds": t1, "runs_per_second": runs / t1,
                 "compute_seconds": ref.seconds})
    t2, r2 = median_time(lambda: design.monte_carlo(runs=runs, threads=2), repeat)
    rows.append({"how": "C++ thread pool, 2 threads", "seconds": t2, "runs_per_second": runs / t2,
                 "compute_seconds": r2.seconds})
    for n in (1, 2):
        with LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None,
                          silence_logs=40) as cluster, Client(cluster) as client:
            distributed.monte_carlo(client, case, runs=4 * n, chunk=1)  # start-up: every worker builds the case
            tn, rn = median_time(lambda: distributed.monte_carlo(client, case, runs=runs, chunk=chunk), repeat)
            assert np.array_equal(rn.observed, ref.observed), "the Dask batch differs from the single-process one"
            rows.append({"how": f"Dask, {n} worker process{'es' if n > 1 else ''} (chunks of {chunk})", "seconds": tn,
                         "runs_per_second": runs / tn, "compute_seconds": rn.seconds})
    for r in rows:
        r["speedup"] = t1 / r["seconds"]
    return {"case": "Example 3, LQR (Q = I, R = 0.1 I)", "runs": runs, "rows": rows}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--repeat", type=int, default=3, help="repetitions of each Monte Carlo timing")
    parser.add_argument("--runs", type=int, default=200)
    args = parser.parse_args()
    out = {"load_average": os.getloadavg(), "cores": os.cpu_count()}
    out["simulate"] = simulate_overhead(200)
    out["jump_gains"] = jump_gain_overhead(200)
    out["python_input_law"] = python_input_law_cost(20)
    out["dask_monte_carlo"] = dask_batch(args.runs, 25, args.repeat)
    if args.json:
        print(json.dumps(out, indent=2))
        return 0
    la = out["load_average"]
    print(f"load average {la[0]:.2f} {la[1]:.2f} {la[2]:.2f} on {out['cores']} cores")
    s = out["simulate"]
    print(f"simulate ({s['case']}, {s['events']} events): Python {s['python_seconds'] * 1e6:.1f} us, C++ run "
          f"{s['cpp_seconds'] * 1e6:.1f} us: overhead {s['overhead_seconds'] * 1e6:.1f} us per call "
          f"({100 * s['overhead_fraction']:.0f} %); reading segments and events {s['read_segments_events_seconds'] * 1e6:.1f} us")
    j = out["jump_gains"]
    print(f"jump_gains: {j['seconds'][0] * 1e6:.1f} us for {j['events'][0]} event, {j['seconds'][1] * 1e6:.1f} us for "
          f"{j['events'][1]}: {j['cpp_seconds_per_gain'] * 1e6:.2f} us per gain, {j['overhead_seconds_per_call'] * 1e6:.1f} us "
          "overhead per call")
    p = out["python_input_law"]
    print(f"input law ({p['case']}): C++ {p['cpp_law_seconds'] * 1e3:.2f} ms, Python callable "
          f"{p['python_law_seconds'] * 1e3:.2f} ms (x{p['ratio']:.1f}, {p['law_calls_per_run']:.0f} calls, "
          f"{p['seconds_per_python_call'] * 1e6:.2f} us per call)")
    d = out["dask_monte_carlo"]
    print(f"Monte Carlo, {d['case']}, {d['runs']} runs:")
    for r in d["rows"]:
        print(f"  {r['how']:42s} {r['seconds']:6.2f} s  {r['runs_per_second']:6.1f} runs/s  speed-up "
              f"{r['speedup']:.2f}  (simulations {r['compute_seconds']:.2f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
