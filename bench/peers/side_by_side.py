#!/usr/bin/env python3
"""NOSNOC (nosnoc_py, CasADi, Ipopt) and Saltus side by side on the same problems, in the same run.

Problems:
  particle  NOSNOC's time-freezing particle example: a point mass from (0, 1) m with velocity (3, 0) m/s
            falls onto the ground (g = 10, e = 0, Coulomb mu = 0.2) and slides to rest; 2.5 s in 20 steps
            of 0.125 s. Closed form: lands at t = sqrt(0.2) s with v_x = 3 - mu sqrt(2 g) (the impact's
            friction impulse), stops at t = 1.5 s at x = 2.45 m.
  hopper    the hopper over three holes of the time-freezing paper (Section 6): T = 2.5 s, |u| <= 60 N m,
            N = 20, 3 finite elements, Radau IIA n_s = 2, speed of time in [1, 5], sigma_0 = 1,
            kappa = 0.1; from (0, 0.4, 0, 0) at rest to (3, 0.4, 0, 0); the path rows and hole ellipses
            of examples/scenes/hopper_holes.hpp.

Each (problem, implementation) runs in a child process of its own (the two sides live in different
Python environments: NOSNOC in a venv with the CasADi wheel, Saltus from the build's bindings), one
after the other, with one BLAS/OpenMP thread. The parent prints one table row per run and writes all
rows to a JSON file.

  python3 bench/peers/side_by_side.py [--problem particle|hopper|all] [--side nosnoc|saltus|both]
      [--nosnoc-python VENV/bin/python] [--saltus-pythonpath build/python] [--runs 1] [--json rows.json]

A benchmark only: nothing in the library, its CMake build or its tests uses this file.
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

# ---------------------------------------------------------------------------------------------------
# The problems' data (one place for both sides).
# ---------------------------------------------------------------------------------------------------

PARTICLE = dict(gravity=10.0, mu=0.2, a_n=20.0, q0=(0.0, 1.0), v0=(3.0, 0.0), steps=20, step=0.125,
                finite_elements=5)


def particle_closed_form():
    """Final state (x, z, v_x, v_z) at t = 2.5 s and the landing and stop times."""
    g, mu = PARTICLE["gravity"], PARTICLE["mu"]
    t_land = math.sqrt(2.0 * PARTICLE["q0"][1] / g)
    v_n = g * t_land  # normal speed at impact
    v_t = PARTICLE["v0"][0] - mu * v_n  # after the impact's Coulomb impulse (slip throughout)
    t_stop = t_land + v_t / (mu * g)
    x_stop = PARTICLE["v0"][0] * t_land + v_t * v_t / (2.0 * mu * g)
    return (x_stop, 0.0, 0.0, 0.0), t_land, t_stop


# The hopper (examples/scenes/hopper.hpp defaults; q = (x, z, phi_hip, phi_knee), u = joint torques).
HOPPER = dict(base_mass=3.975, thigh_mass=1.782, shank_mass=0.548, thigh_length=0.2, shank_length=0.2,
              thigh_com=0.016, shank_com=0.1, thigh_inertia=0.001, shank_inertia=0.0032, gravity=9.81,
              mu=0.8, a_n=200.0)
HOLES = dict(centres=(0.5, 1.5, 2.5), half_width=0.25, depth=0.1)
HOPPER_OCP = dict(T=2.5, N=20, finite_elements=3, n_s=2, torque=60.0, sot=(1.0, 5.0), rho_sot=0.01, rho_h=1.0,
                  q0=(0.0, 0.4, 0.0, 0.0), q_target=(3.0, 0.4, 0.0, 0.0), sigma_0=1.0, kappa=0.1,
                  homotopy_steps=10, comp_tol=1e-10, max_iter=1500)


def hole_values(foot_x, foot_z):
    """The three ellipse values ((x - x_c) / a)^2 + (z / b)^2 at one foot position (>= 1: outside)."""
    a, b = HOLES["half_width"], HOLES["depth"]
    return [((foot_x - c) / a) ** 2 + (foot_z / b) ** 2 for c in HOLES["centres"]]


# ---------------------------------------------------------------------------------------------------
# NOSNOC side (run with the venv's Python).
# ---------------------------------------------------------------------------------------------------

def _nosnoc_common_opts(ns):
    opts = ns.NosnocOpts()
    opts.pss_mode = ns.PssMode.STEP
    opts.use_fesd = True
    opts.irk_scheme = ns.IrkSchemes.RADAU_IIA
    opts.irk_representation = ns.IrkRepresentation.INTEGRAL
    opts.mpcc_mode = ns.MpccMode.SCHOLTES_INEQ
    opts.homotopy_update_rule = ns.HomotopyUpdateRule.LINEAR
    opts.step_equilibration = ns.StepEquilibrationMode.HEURISTIC_MEAN
    opts.print_level = 1  # one line per homotopy step, parsed by _homotopy
    # NosnocOpts keeps its Ipopt options in a class-level dict: give this instance a copy of its own.
    opts.opts_casadi_nlp = json.loads(json.dumps(opts.opts_casadi_nlp))
    opts.opts_casadi_nlp["ipopt"]["print_level"] = 0
    opts.opts_casadi_nlp["ipopt"]["linear_solver"] = "mumps"
    return opts


def _lifted_step_weights(ca, alpha):
    """The time-freezing region weights (time-freezing paper eq. 32), lifted: beta = (1 - a1)(1 - a2)
    as an algebraic variable, theta = (1 - beta, beta (1 - a3), beta a3) for (free flight, the
    auxiliary dynamics with v_t < 0, with v_t > 0)."""
    beta = ca.SX.sym("beta")
    theta = ca.SX.sym("theta", 3)
    g_z = ca.vertcat(beta - (1 - alpha[0]) * (1 - alpha[1]),
                     theta[0] - (1 - beta),
                     theta[1] - beta * (1 - alpha[2]),
                     theta[2] - beta * alpha[2])
    return ca.vertcat(theta, beta), theta, g_z


def _nlp_violation(np, prob, w, p):
    """Largest violation of the NLP's constraint rows and variable bounds at (w, p)."""
    g = prob.g_fun(w, p).full().flatten()
    lbg, ubg = np.asarray(prob.lbg, float), np.asarray(prob.ubg, float)
    viol = np.maximum(np.maximum(lbg - g, g - ubg), 0.0)
    lbw, ubw = np.asarray(prob.lbw, float), np.asarray(prob.ubw, float)
    viol_w = np.maximum(np.maximum(lbw - w, w - ubw), 0.0)
    return float(max(viol.max(initial=0.0), viol_w.max(initial=0.0)))


def _homotopy(np, solver, record):
    """NosnocSolver.solve() and the statistics it computes but does not return: each homotopy step's
    sigma, complementarity residual (max of the products, nosnoc_py's comp_res), objective, Ipopt
    CPU time, iterations and return status (parsed from its print_level 1 lines), and the NLP's
    constraint violation at the last step's sigma."""
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        res = solver.solve()
    for line in buf.getvalue().splitlines():
        f = line.split()
        if len(f) == 7 and f[0][0].isdigit():
            record["steps"].append(dict(sigma=float(f[0]), complementarity=float(f[1]), objective=float(f[3]),
                                        cpu_s=float(f[4]), ipopt_iterations=int(f[5]), status=f[6]))
    prob = solver.problem
    w = res["w_sol"]
    record["ipopt_iterations"] += int(sum(i for i in res["nlp_iter"] if i is not None))
    record["homotopy_steps"] += int(sum(1 for i in res["nlp_iter"] if i is not None))
    comp = float(prob.comp_res(w, solver.p_val).full()[0][0])
    record["complementarity"] = max(record["complementarity"], comp)
    record["constraint_violation"] = max(record["constraint_violation"], _nlp_violation(np, prob, w, solver.p_val))
    record["ipopt_status"] = solver.solver.stats()["return_status"]
    return res


def _step_summary(steps):
    """Ipopt return statuses of the homotopy steps, counted."""
    counts = {}
    for st in steps:
        counts[st["status"]] = counts.get(st["status"], 0) + 1
    return counts


def nosnoc_particle():
    import numpy as np
    import casadi as ca
    import nosnoc as ns

    P = PARTICLE
    g, mu, a_n = P["gravity"], P["mu"], P["a_n"]
    q = ca.SX.sym("q", 2)
    v = ca.SX.sym("v", 2)
    t = ca.SX.sym("t")
    alpha = ca.SX.sym("alpha", 3)
    z, theta, g_z = _lifted_step_weights(ca, alpha)
    # Switching functions: gap, normal velocity, tangential velocity.
    c = ca.vertcat(q[1], v[1], v[0])
    f_free = ca.vertcat(v, 0.0, -g, 1.0)
    f_aux_n = ca.vertcat(0.0, 0.0, 0.0, a_n, 0.0)
    f_aux_t = ca.vertcat(0.0, 0.0, mu * a_n, 0.0, 0.0)
    f_x = theta[0] * f_free + theta[1] * (f_aux_n + f_aux_t) + theta[2] * (f_aux_n - f_aux_t)
    x0 = np.array([*P["q0"], *P["v0"], 0.0])
    model = ns.NosnocModel(x=ca.vertcat(q, v, t), f_x=[f_x], alpha=[alpha], c=[c], x0=x0, t_var=t, z=z,
                           z0=np.array([1.0, 0.0, 0.0, 0.0]), g_z=g_z, name="particle")

    opts = _nosnoc_common_opts(ns)
    opts.n_s = 2
    opts.sigma_0 = 1.0
    opts.homotopy_update_slope = 0.1
    opts.cross_comp_mode = ns.CrossComplementarityMode.COMPLEMENT_ALL_STAGE_VALUES_WITH_EACH_OTHER
    opts.time_freezing = True
    opts.time_freezing_tolerance = 0.0
    opts.equidistant_control_grid = True
    opts.speed_of_time_variables = ns.SpeedOfTimeVariableMode.LOCAL
    opts.N_finite_elements = P["finite_elements"]
    opts.max_iter_homotopy = 9
    opts.terminal_time = P["step"]

    record = dict(ipopt_iterations=0, homotopy_steps=0, complementarity=0.0, constraint_violation=0.0, steps=[])
    t0 = time.perf_counter()
    solver = ns.NosnocSolver(opts, model)
    setup = time.perf_counter() - t0
    xk = x0.copy()
    statuses = []
    for _ in range(P["steps"]):
        solver.set("x0", xk)
        res = _homotopy(np, solver, record)
        statuses.append(record["ipopt_status"])
        xk = np.asarray(res["x_list"][-1]).flatten()
    wall = time.perf_counter() - t0
    final, _, _ = particle_closed_form()
    err = float(np.max(np.abs(xk[:4] - np.array(final))))
    failed = [(k, s) for k, s in enumerate(statuses) if s not in ("Solve_Succeeded", "Solved_To_Acceptable_Level")]
    return dict(problem="particle", implementation="NOSNOC", wall_s=wall, setup_s=setup, solve_s=wall - setup,
                ipopt_iterations=record["ipopt_iterations"], homotopy_steps=record["homotopy_steps"],
                complementarity=record["complementarity"], constraint_violation=record["constraint_violation"],
                objective=None, final_state=xk.tolist(), final_state_error=err,
                step_statuses=_step_summary(record["steps"]),
                status="all steps solved" if not failed else "; ".join(f"step {k + 1} of {len(statuses)}: {s}" for k, s in failed),
                note="20 FESD time-freezing steps of 0.125 s, 5 elements, n_s = 2, sigma 1 -> 1e-8 (9 steps); "
                     "complementarity and violation: the largest over the 20 steps")


def _hopper_dynamics(ca):
    """M(q), the bias h(q, v) (M qdd + h = S u) from the Lagrangian, foot and knee positions; the
    kinematics of examples/scenes/hopper.hpp (foot = hip + l (sin, -cos))."""
    p = HOPPER
    q = ca.SX.sym("q", 4)
    v = ca.SX.sym("v", 4)
    x, zc, a1, a2 = q[0], q[1], q[2], q[3]
    hip = ca.vertcat(x, zc)

    def down(angle, length):
        return length * ca.vertcat(ca.sin(angle), -ca.cos(angle))

    knee = hip + down(a1, p["thigh_length"])
    foot = knee + down(a1 + a2, p["shank_length"])
    thigh_com = hip + down(a1, p["thigh_com"])
    shank_com = knee + down(a1 + a2, p["shank_com"])
    bodies = [(p["base_mass"], hip), (p["thigh_mass"], thigh_com), (p["shank_mass"], shank_com)]
    kinetic = 0.5 * p["thigh_inertia"] * v[2] ** 2 + 0.5 * p["shank_inertia"] * (v[2] + v[3]) ** 2
    potential = 0
    for m, pos in bodies:
        vel = ca.jtimes(pos, q, v)
        kinetic += 0.5 * m * ca.dot(vel, vel)
        potential += m * p["gravity"] * pos[1]
    M = ca.hessian(kinetic, v)[0]
    lagrangian = kinetic - potential
    # Euler-Lagrange: M qdd + (d/dq (M v)) v - dL/dq = S u.
    bias = ca.jtimes(ca.mtimes(M, v), q, v) - ca.gradient(lagrangian, q)
    return q, v, M, bias, foot, knee


def nosnoc_hopper():
    import numpy as np
    import casadi as ca
    import nosnoc as ns

    o, p = HOPPER_OCP, HOPPER
    q, v, M, bias, foot, knee = _hopper_dynamics(ca)
    t = ca.SX.sym("t")
    u = ca.SX.sym("u", 3)  # hip and knee torques, speed of time s
    tau, s = u[:2], u[2]
    alpha = ca.SX.sym("alpha", 3)
    z, theta, g_z = _lifted_step_weights(ca, alpha)
    # Contact directions as in the paper's script: unit gradients of foot_z and foot_x.
    J_n = ca.jacobian(foot[1], q).T
    J_t = ca.jacobian(foot[0], q).T
    n = J_n / ca.norm_2(J_n)
    tng = J_t / ca.norm_2(J_t)
    Minv = ca.inv(M)
    qdd = ca.mtimes(Minv, ca.vertcat(0.0, 0.0, tau) - bias)
    f_ode = ca.vertcat(v, qdd, 1.0)
    f_aux_n = ca.vertcat(ca.SX.zeros(4), ca.mtimes(Minv, n) * p["a_n"], 0.0)
    f_aux_t = ca.vertcat(ca.SX.zeros(4), ca.mtimes(Minv, tng) * p["mu"] * p["a_n"], 0.0)
    # Regions: free (gap > 0 or n'v > 0); auxiliary dynamics, friction against the sign of t'v.
    f_x = s * (theta[0] * f_ode + theta[1] * (f_aux_n + f_aux_t) + theta[2] * (f_aux_n - f_aux_t))
    c = ca.vertcat(foot[1], ca.dot(n, v), ca.dot(tng, v))
    x0 = np.array([*o["q0"], 0.0, 0.0, 0.0, 0.0, 0.0])
    # The path rows are imposed on x_0 .. x_{N-1} (the paper's script): nosnoc_py evaluates them at the
    # end of each control interval, so a stage parameter switches them off on the last one (x_N is
    # pinned by the terminal rows; x_0 is fixed).
    gate = ca.SX.sym("gate")
    gate_val = np.ones((o["N"], 1))
    gate_val[-1, 0] = 0.0
    model = ns.NosnocModel(x=ca.vertcat(q, v, t), f_x=[f_x], alpha=[alpha], c=[c], x0=x0, u=u, z=z,
                           z0=np.array([1.0, 0.0, 0.0, 0.0]), g_z=g_z, p_time_var=gate, p_time_var_val=gate_val,
                           name="hopper")

    # The 11 path rows of examples/scenes/hopper_holes.hpp, written as gate * (row - bound) >= 0.
    pi = math.pi
    rows = [(q[0], -0.05, None), (foot[0], -0.05, None), (knee[0], -0.05, None), (q[1], 0.2, 0.55),
            (q[2], -3 * pi / 8, 3 * pi / 8), (q[3], -pi / 2, pi / 2), (knee[1], 0.05, None),
            (foot[1], -0.005, 0.2)]
    a, b = HOLES["half_width"], HOLES["depth"]
    for xc in HOLES["centres"]:
        rows.append((((foot[0] - xc) / a) ** 2 + (foot[1] / b) ** 2, 1.0, None))
    g_path = []
    for expr, lo, hi in rows:
        if lo is not None:
            g_path.append(gate * (expr - lo))
        if hi is not None:
            g_path.append(gate * (hi - expr))
    g_path = ca.vertcat(*g_path)
    n_rows = g_path.shape[0]
    # Cost: s u'u (the integral over physical time) and rho_sot (s - 1)^2 per interval as an integrand
    # scaled by N / T; the numerical length of each interval is T / N (equidistant grid).
    f_q = s * ca.dot(tau, tau) + o["rho_sot"] * (s - 1) ** 2 * o["N"] / o["T"]
    ocp = ns.NosnocOcp(lbu=np.array([-o["torque"], -o["torque"], o["sot"][0]]),
                       ubu=np.array([o["torque"], o["torque"], o["sot"][1]]), u_guess=np.array([0.0, 0.0, 1.0]),
                       f_q=f_q, g_path=g_path, lbg=np.zeros(n_rows), ubg=np.full(n_rows, np.inf),
                       g_terminal=ca.vertcat(q - np.array(o["q_target"]), t - o["T"]))

    opts = _nosnoc_common_opts(ns)
    opts.n_s = o["n_s"]
    opts.N_stages = o["N"]
    opts.N_finite_elements = o["finite_elements"]
    opts.terminal_time = o["T"]
    opts.equidistant_control_grid = True
    opts.rho_h = o["rho_h"]
    opts.cross_comp_mode = ns.CrossComplementarityMode.SUM_LAMBDAS_COMPLEMENT_WITH_EVERY_THETA
    opts.sigma_0 = o["sigma_0"]
    opts.homotopy_update_slope = o["kappa"]
    opts.max_iter_homotopy = o["homotopy_steps"]
    opts.comp_tol = o["comp_tol"]
    opts.sigma_N = 0.0  # stop on comp_tol or the step count only
    opts.time_freezing = False  # the terminal clock row only (the paper: no stage-wise clock rows)
    opts.opts_casadi_nlp["ipopt"]["max_iter"] = o["max_iter"]

    record = dict(ipopt_iterations=0, homotopy_steps=0, complementarity=0.0, constraint_violation=0.0, steps=[])
    t0 = time.perf_counter()
    solver = ns.NosnocSolver(opts, model, ocp)
    setup = time.perf_counter() - t0
    res = _homotopy(np, solver, record)
    wall = time.perf_counter() - t0
    prob, w = solver.problem, res["w_sol"]
    # Objective: the integral of u'u over physical time = sum_k s_k |u_k|^2 T / N.
    U = np.array([np.asarray(uk).flatten() for uk in res["u_list"]])
    objective = float(np.sum(U[:, 2] * np.sum(U[:, :2] ** 2, axis=1)) * o["T"] / o["N"])
    nlp_objective = float(prob.cost_fun(w, solver.p_val).full()[0][0])
    # Foot positions at every stage point and element boundary of the solution.
    foot_fun = ca.Function("foot", [q], [foot])
    points = []
    for xk in res["x_all_list"]:
        xk = np.asarray(xk, dtype=float)
        points.extend(xk.reshape(-1, 9) if xk.size % 9 == 0 else [xk[:9]])
    points = np.array(points)
    feet = np.array([np.asarray(foot_fun(pt[:4])).flatten() for pt in points])
    holes = np.array([hole_values(fx, fz) for fx, fz in feet])
    # ... and at the control nodes x_1 .. x_{N-1}, where the rows are imposed.
    nodes = [np.asarray(xk, dtype=float).flatten() for xk in res["x_list"]][o["finite_elements"] - 1::o["finite_elements"]]
    node_holes = [min(hole_values(*np.asarray(foot_fun(xk[:4])).flatten())) for xk in nodes[:-1]]
    x_end = np.asarray(res["x_list"][-1]).flatten()
    target_error = float(np.max(np.abs(x_end[:4] - np.array(o["q_target"]))))
    converged = record["complementarity"] < o["comp_tol"] and record["ipopt_status"] in (
        "Solve_Succeeded", "Solved_To_Acceptable_Level")
    return dict(problem="hopper", implementation="NOSNOC", wall_s=wall, setup_s=setup, solve_s=wall - setup,
                ipopt_iterations=record["ipopt_iterations"], homotopy_steps=record["homotopy_steps"],
                complementarity=record["complementarity"], constraint_violation=record["constraint_violation"],
                objective=objective, nlp_objective=nlp_objective, min_hole_ellipse=float(holes.min()),
                min_hole_ellipse_control_nodes=float(min(node_holes)),
                min_foot_z=float(feet[:, 1].min()), target_error=target_error, clock_end=float(x_end[8]),
                homotopy=record["steps"],
                status=("converged" if converged else "not converged") + f" (last step: {record['ipopt_status']})",
                note="objective: sum_k s_k |u_k|^2 T/N; hole value over all stage points and element boundaries")


# ---------------------------------------------------------------------------------------------------
# Saltus side (run with /usr/bin/python3 and the build's bindings on PYTHONPATH).
# ---------------------------------------------------------------------------------------------------

def saltus_particle():
    import numpy as np
    import saltus

    P = PARTICLE
    scene = saltus.PointMass(1.0, P["gravity"], "planar", P["mu"], 0.0)
    x0 = np.array([*P["q0"], *P["v0"]])
    t_final = P["steps"] * P["step"]
    t0 = time.perf_counter()
    traj = saltus.simulate(scene, x0, 0.0, t_final)
    wall = time.perf_counter() - t0
    final, t_land, t_stop = particle_closed_form()
    xf = np.asarray(traj.final_state).flatten()
    times = [e.t for e in traj.events]
    time_err = max(abs(times[0] - t_land), abs(times[-1] - t_stop)) if len(times) >= 2 else None
    return dict(problem="particle", implementation="Saltus", wall_s=wall, setup_s=0.0, solve_s=wall,
                ipopt_iterations=0, homotopy_steps=0, complementarity=0.0, constraint_violation=None,
                objective=None, final_state=xf.tolist(), final_state_error=float(np.max(np.abs(xf - np.array(final)))),
                event_times=times, event_time_error=time_err, status=str(traj.status),
                note="event-driven simulation (saltus.simulate on PointMass, Coulomb impact law, CVODE): no NLP, "
                     "complementarity exact by construction; the bindings have no time-freezing simulation")


def saltus_hopper(runs):
    import numpy as np
    import saltus

    lines = []
    t0 = time.perf_counter()
    r = saltus.optimal_control.hopper_over_three_holes(progress=lines.append, initialisation="paper", runs=runs,
                                                        deviation_times=0)
    wall = time.perf_counter() - t0
    steps = (r.get("discovery") or {}).get("steps", [])
    disc_iters = int(sum(s.get("ipopt_iterations", 0) for s in steps))
    ref_iters = int((r.get("refinement") or {}).get("ipopt_iterations", 0) or 0)
    relaxed_comp = steps[-1].get("complementarity") if steps else None
    min_hole, min_foot_z = None, None
    ref = r.get("reference")
    if ref is not None:
        hopper = saltus.Hopper()
        ts = np.linspace(ref.t_begin, ref.t_end, 5001)
        ts = np.unique(np.concatenate([ts, np.asarray(r.get("event_times", []), dtype=float)]))
        X = np.asarray(ref.sample(ts))
        feet = np.array([np.asarray(hopper.foot(xk[:4])).flatten() for xk in X])
        min_hole = float(min(min(hole_values(fx, fz)) for fx, fz in feet))
        min_foot_z = float(feet[:, 1].min())
    converged = bool(r.get("converged"))
    return dict(problem="hopper", implementation="Saltus", wall_s=wall,
                setup_s=0.0, solve_s=float(r.get("discovery_seconds", 0.0)) + float(r.get("refinement_seconds", 0.0)),
                discovery_s=r.get("discovery_seconds"), refinement_s=r.get("refinement_seconds"),
                ipopt_iterations=disc_iters + ref_iters, discovery_iterations=disc_iters, refinement_iterations=ref_iters,
                homotopy_steps=len(steps),
                complementarity=0.0 if converged else relaxed_comp, relaxed_complementarity=relaxed_comp,
                constraint_violation=max(float(r.get("max_path_violation") or 0.0), float(r.get("target_error") or 0.0))
                if "max_path_violation" in r else None,
                mode_validity_violation=r.get("mode_validity_violation"),
                phase_resim_max_error=r.get("phase_resim_max_error"),
                objective=r.get("objective"), relaxed_objective=r.get("relaxed_objective"),
                min_hole_ellipse=min_hole, min_foot_z=min_foot_z, target_error=r.get("target_error"),
                schedule=r.get("schedule"), status=str(r.get("stage")),
                homotopy=[dict(sigma=st.get("sigma"), complementarity=st.get("complementarity"),
                               objective=st.get("objective"), cpu_s=st.get("seconds"),
                               ipopt_iterations=st.get("ipopt_iterations"), status=st.get("ipopt_status"))
                          for st in steps],
                note="discovery (FESD time-freezing homotopy) + mode-schedule refinement; complementarity 0 by "
                     "construction when refined; violation: max(path rows, target error) of the refined reference; "
                     f"analysis with runs = {runs}; hole value sampled at 5001 times and the events")


# ---------------------------------------------------------------------------------------------------
# The driver.
# ---------------------------------------------------------------------------------------------------

WORKERS = {("particle", "nosnoc"): nosnoc_particle, ("hopper", "nosnoc"): nosnoc_hopper,
           ("particle", "saltus"): saltus_particle, ("hopper", "saltus"): None}


def run_worker(problem, side, runs):
    if (problem, side) == ("hopper", "saltus"):
        row = saltus_hopper(runs)
    else:
        row = WORKERS[(problem, side)]()
    row["versions"] = _versions(side)
    print("@@ROW " + json.dumps(row, default=_jsonable), flush=True)


def _jsonable(o):
    try:
        return float(o)
    except (TypeError, ValueError):
        return str(o)


def _versions(side):
    v = {"python": sys.version.split()[0]}
    if side == "nosnoc":
        import casadi
        import numpy
        from importlib.metadata import version
        v.update(nosnoc=version("nosnoc"), casadi=casadi.__version__, numpy=numpy.__version__)
    else:
        import numpy
        v.update(numpy=numpy.__version__)
    return v


def child_env(args, side):
    env = dict(os.environ)
    for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        env[k] = "1"
    if side == "saltus":
        env["PYTHONPATH"] = os.path.abspath(args.saltus_pythonpath) + (
            os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def fmt(x, spec):
    if x is None:
        return "-"
    if isinstance(x, str):
        return x
    return format(x, spec)


def print_table(rows):
    head = ("problem", "implementation", "wall [s]", "Ipopt iter", "complementarity", "violation", "objective",
            "min hole value", "status")
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for r in rows:
        if "error" in r:
            print(f"| {r['problem']} | {r['implementation']} | - | - | - | - | - | - | failed: {r['error']} |")
            continue
        print("| " + " | ".join([
            r["problem"], r["implementation"], fmt(r.get("wall_s"), ".2f" if (r.get("wall_s") or 0) >= 0.01 else ".1e"), fmt(r.get("ipopt_iterations"), "d"),
            fmt(r.get("complementarity"), ".2e"), fmt(r.get("constraint_violation"), ".2e"),
            fmt(r.get("objective"), ".4g"), fmt(r.get("min_hole_ellipse"), ".5f"), r.get("status", "")]) + " |")
    shown = {"problem", "implementation", "wall_s", "ipopt_iterations", "complementarity", "constraint_violation",
             "objective", "min_hole_ellipse", "status", "versions", "schedule"}
    for r in rows:
        extra = {k: v for k, v in r.items() if k not in shown and k != "error"}
        print(f"\n{r['problem']} / {r['implementation']}:")
        for k, v in extra.items():
            if k == "homotopy":
                print("  homotopy (sigma, complementarity, objective, Ipopt s, iterations, status):")
                for st in v:
                    print(f"    {st['sigma']:.0e}  {fmt(st.get('complementarity'), '.2e')}  "
                          f"{fmt(st.get('objective'), '.3g')}  {fmt(st.get('cpu_s'), '.1f')}  "
                          f"{st.get('ipopt_iterations')}  {st.get('status')}")
                continue
            print(f"  {k}: {fmt(v, '.6g') if isinstance(v, float) else v}")
        print(f"  versions: {r.get('versions')}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--problem", choices=("particle", "hopper", "all"), default="all")
    ap.add_argument("--side", choices=("nosnoc", "saltus", "both"), default="both")
    ap.add_argument("--nosnoc-python", default=os.environ.get("NOSNOC_PYTHON", sys.executable),
                    help="a Python with `pip install nosnoc` (default: $NOSNOC_PYTHON, else this interpreter)")
    ap.add_argument("--saltus-python", default="/usr/bin/python3", help="the Python the bindings were built for")
    ap.add_argument("--saltus-pythonpath", default=os.path.join(ROOT, "build", "python"),
                    help="the directory holding the `saltus` package (the build's python/)")
    ap.add_argument("--runs", type=int, default=1,
                    help="Monte Carlo runs of the Saltus hopper's closed-loop analysis (not timed as solve)")
    ap.add_argument("--json", default="side_by_side.json", help="where to write the rows")
    ap.add_argument("--worker", nargs=2, metavar=("PROBLEM", "SIDE"), help=argparse.SUPPRESS)
    args = ap.parse_args()

    if args.worker:
        run_worker(args.worker[0], args.worker[1], args.runs)
        return

    problems = ("particle", "hopper") if args.problem == "all" else (args.problem,)
    sides = ("nosnoc", "saltus") if args.side == "both" else (args.side,)
    rows = []
    for problem in problems:
        for side in sides:
            python = args.nosnoc_python if side == "nosnoc" else args.saltus_python
            cmd = [python, os.path.abspath(__file__), "--worker", problem, side, "--runs", str(args.runs)]
            print(f"# running {problem} / {side} ...", file=sys.stderr, flush=True)
            t0 = time.perf_counter()
            proc = subprocess.run(cmd, env=child_env(args, side), capture_output=True, text=True)
            elapsed = time.perf_counter() - t0
            row = None
            for line in proc.stdout.splitlines():
                if line.startswith("@@ROW "):
                    row = json.loads(line[6:])
            if row is None:
                tail = (proc.stderr or proc.stdout).strip().splitlines()[-3:]
                row = dict(problem=problem, implementation="NOSNOC" if side == "nosnoc" else "Saltus",
                           error=" / ".join(tail) or f"exit code {proc.returncode}")
            row["process_s"] = elapsed
            rows.append(row)
            print(f"# {problem} / {side}: {elapsed:.1f} s", file=sys.stderr, flush=True)
    print_table(rows)
    load = os.getloadavg()
    with open(args.json, "w") as f:
        json.dump(dict(rows=rows, loadavg_at_end=load, nproc=os.cpu_count()), f, indent=1, default=_jsonable)
    print(f"\nload average at the end (1, 5, 15 min): {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; rows in {args.json}")


if __name__ == "__main__":
    main()
