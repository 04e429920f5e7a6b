"""A user's own C++ scene in Python: FallingMass (a unit mass above the ground under a vertical
thrust u) bound by one macro in the extension module falling_mass_python
(examples/python/user_scene/: falling_mass.hpp, falling_mass.cpp, falling_mass_python.cpp;
built by python/CMakeLists.txt beside the package). Simulates a drop from 2 m, checks the
touchdown time sqrt(2 h / g), the gain of the inelastic impact, a bad state, and the stability of
a PD design that holds the mass on the ground.

    PYTHONPATH=<build>/python /usr/bin/python3 examples/python/user_scene/user_scene.py
"""
import math
import sys

import numpy as np

import falling_mass_python as fm
import saltus

scene = fm.FallingMass()
traj = fm.simulate(scene, np.array([2.0, 0.0]), 0.0, 1.0, input=[0.0])
t_touch = math.sqrt(2 * 2.0 / 9.81)
ev = traj.events[0]
print(f"{type(traj).__name__}: {len(traj.events)} event at t = {ev.t:.12f} s (closed form {t_touch:.12f}), "
      f"{ev.mode_before} -> {ev.mode_after}, v- = {ev.x_minus[1]:.4f} m/s, v+ = {ev.x_plus[1]:.1e} m/s")
gain = fm.jump_gains(traj)[0]
print(f"jump gain ({type(gain).__module__}.{type(gain).__name__}):\n{gain.G_z}")
try:
    fm.simulate(scene, np.array([2.0, 0.0, 1.0]), 0.0, 1.0)
    raised = None
except saltus.InvalidArgument as e:  # the library's exception, translated by saltus._saltus
    raised = e
print(f"a state of size 3: saltus.InvalidArgument: {raised}")

# A PD law on the height (kp 100 N/m, kd 20 N s/m) along the drop: the inelastic impact into
# closed contact forgets every deviation (G_z = 0), so the check finds a(T) = 0 after it.
lin = fm.linearise(traj, spreading=0.05)
design = fm.tracking(lin, fm.constant_gains(lin, saltus.pd_gain([[100.0]], [[20.0]])))
report = design.check_stability()
print(f"PD (100, 20) along the drop: {report.verdict}, a(T) <= {report.upper_bound:.4g}")

ok = (abs(ev.t - t_touch) < 1e-9 and ev.guards == [(0, "ground", "touchdown")] and ev.x_plus[1] == 0.0
      and isinstance(gain, saltus.JumpGain) and gain.G_z[1, 1] == 0.0 and raised is not None
      and "expected nx = 2 nq = 2" in str(raised) and report.verdict == "stable")
sys.exit(0 if ok else 1)
