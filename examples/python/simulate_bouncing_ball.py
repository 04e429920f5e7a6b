"""A ball dropped from 1 m with restitution e_n = 0.5 (examples/bouncing_ball.cpp from Python): the
bounces accumulate in finite time (Zeno) at t_inf = sqrt(2 h / g) (1 + e) / (1 - e). Prints the
events, draws the height against time with the events marked.

    PYTHONPATH=<build>/python /usr/bin/python3 examples/python/simulate_bouncing_ball.py [out.png]
"""
import math
import sys

if len(sys.argv) > 2 or (len(sys.argv) == 2 and sys.argv[1].startswith("-")):
    sys.exit(__doc__)  # usage: one optional argument, the figure's path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import saltus  # noqa: E402

ball = saltus.BouncingBall(mass=0.1, restitution=0.5)
options = saltus.SimulationOptions()
options.relative_tolerance = 1e-12
options.absolute_tolerance = 1e-13
h0, g, e = 1.0, ball.gravity, ball.restitution
traj = saltus.simulate(ball, np.array([h0, 0.0]), 0.0, 5.0, options=options)

t_inf = math.sqrt(2 * h0 / g) * (1 + e) / (1 - e)
print(f"bouncing ball, e_n = {e}, dropped from {h0} m: {len(traj.events)} bounces, status {traj.status}")
print(f"  first bounce at t = {traj.events[0].t:.15f} s (closed form {math.sqrt(2 * h0 / g):.15f})")
print(f"  accumulation predicted at {traj.zeno_time:.12f} s (closed form {t_inf:.12f}, "
      f"error {abs(traj.zeno_time - t_inf):.2e})")
for ev in traj.events[:4]:
    print(f"  t = {ev.t:.6f} s  {ev.guards[0][1]} {ev.guards[0][2]}: v- = {ev.x_minus[1]:+.4f} m/s -> "
          f"v+ = {ev.x_plus[1]:+.4f} m/s  ({ev.mode_before} -> {ev.mode_after})")

fig, (ax_q, ax_v) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
t = np.linspace(traj.t_begin, traj.t_end, 2000)
x = traj.sample(t)
ax_q.plot(t, x[:, 0], color="C0", lw=1)
for s in traj.segments:  # the integrator's step points
    ax_q.plot(s.times, s.states[:, 0], ".", color="C0", ms=2)
ax_v.plot(t, x[:, 1], color="C1", lw=1)
for ev in traj.events:
    ax_v.plot([ev.t, ev.t], [ev.x_minus[1], ev.x_plus[1]], color="0.6", lw=0.8)
ax_q.axvline(t_inf, color="k", ls=":", lw=0.8, label=f"Zeno time {traj.zeno_time:.4f} s")
ax_q.set_ylabel("height q [m]")
ax_v.set_ylabel("velocity v [m/s]")
ax_v.set_xlabel("t [s]")
ax_q.legend(loc="upper right")
ax_q.set_title(f"Bouncing ball, e_n = {e}: {len(traj.events)} impacts")
fig.tight_layout()
out = sys.argv[1] if len(sys.argv) > 1 else "bouncing_ball.png"
fig.savefig(out, dpi=120)
print(f"wrote {out}")
sys.exit(0 if traj.status == "zeno" and abs(traj.zeno_time - t_inf) < 1e-6 else 1)
