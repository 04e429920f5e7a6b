"""Jump gains of the guiding example (time-freezing paper, Example 3: impact at sqrt(2/g) s into
frictionless contact, sliding, lift-off at 1.5 s through the state-input guard lambda_n = m g - u2),
and the first-order prediction a gain makes, checked against simulations of the bouncing ball:
the deviation after the impact is G_z z- (z- the deviation before it) up to a remainder that
shrinks like eps^2.

    PYTHONPATH=<build>/python /usr/bin/python3 examples/python/jump_gains.py
"""
import sys

import numpy as np

import saltus

np.set_printoptions(precision=4, suppress=True)
ref = saltus.references.example3()
gains = saltus.jump_gains(ref)
for ev, g in zip(ref.events, gains):
    print(f"t = {ev.t:.6f} s, {ev.guards[0][2]} of '{ev.guards[0][1]}' ({ev.mode_before} -> {ev.mode_after})")
    print("  G_z =\n" + "\n".join("    " + str(row) for row in g.G_z))
    print("  G_v =\n" + "\n".join("    " + str(row) for row in g.G_v))
    print(f"  dt/dz = {g.dt_dz}, dt/dv = {g.dt_dv}")

# The first-order prediction across an impact, checked against simulations: the bouncing ball
# (e_n = 0.5) dropped from 1 m and from 1 m + eps d. Between impacts it flies under gravity alone,
# so deviations move linearly in time (z_q' = z_v) and z- and z+ at the nominal impact time t*
# follow from states sampled before and after it; the remainder z+ - G_z z- shrinks like eps^2.
# (Example 3's inelastic impact would show nothing: on the table the vertical deviation is zero
# whatever it was, and its gain is exact.)
ball = saltus.BouncingBall(restitution=0.5)
options = saltus.SimulationOptions()
options.relative_tolerance = options.absolute_tolerance = 1e-13
nominal = saltus.simulate(ball, [1.0, 0.0], 0.0, 0.6, options=options)
gain, t_star = saltus.jump_gains(nominal)[0], nominal.events[0].t
print(f"\nbouncing ball, impact at t* = {t_star:.6f} s: G_z =\n" + "\n".join("    " + str(r) for r in gain.G_z))
d = np.array([1.0, -0.5])  # m, m/s
dt = 0.05  # s after t*, before the next impact
print("eps       |z+ - G_z z-|   ratio to the previous")
previous, ratios = None, []
for eps in [1e-2, 1e-3, 1e-4]:
    perturbed = saltus.simulate(ball, np.array([1.0, 0.0]) + eps * d, 0.0, 0.6, options=options)
    z_minus = eps * d + np.array([eps * d[1] * t_star, 0.0])
    z_late = perturbed.sample([t_star + dt])[0] - nominal.sample([t_star + dt])[0]
    z_plus = z_late - np.array([z_late[1] * dt, 0.0])
    err = np.linalg.norm(z_plus - gain.G_z @ z_minus)
    if previous is not None:
        ratios.append(previous / err)
    print(f"{eps:.0e}   {err:.3e}       " + (f"{previous / err:.1f}" if previous is not None else "-"))
    previous = err
sys.exit(0 if all(r > 50 for r in ratios) else 1)
