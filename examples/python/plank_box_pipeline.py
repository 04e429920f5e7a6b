"""The plank-box flat landing optimised and analysed from Python (the C++ main job's
`plank_box --json`): the time-freezing homotopy discovers the contact schedule, the mode-schedule
refinement makes the reference exact, the library analyses it (jump gains, LQR tracking, stability
check, Monte Carlo). About two minutes on one core; progress lines on stderr.

    PYTHONPATH=<build>/python /usr/bin/python3 examples/python/plank_box_pipeline.py [runs]
"""
import sys

if len(sys.argv) > 2 or (len(sys.argv) == 2 and not sys.argv[1].isdigit()):
    sys.exit(__doc__)  # usage: one optional argument, the number of Monte Carlo runs

import saltus  # noqa: E402

runs = int(sys.argv[1]) if len(sys.argv) == 2 else 100
r = saltus.optimal_control.plank_box_flat_landing(progress=lambda line: print(line, file=sys.stderr), runs=runs)
print(f"stage: {r['stage']}")
print(f"schedule: {r.get('schedule')}")
print(f"objective {r.get('objective', float('nan')):.4f} (relaxed {r['relaxed_objective']:.4f}), "
      f"mode validity {r.get('mode_validity_violation')}, per-phase re-simulation {r.get('phase_resim_max_error')}")
print(f"discovery {r['discovery_seconds']:.1f} s, refinement {r.get('refinement_seconds', float('nan')):.1f} s")
a = r.get("analysis")
if a:
    m = a["monte_carlo"]
    print(f"analysis: {a['design']}, verdict {a['verdict']}, a(T) in [{a['lower_bound']:.4g}, {a['upper_bound']:.4g}]; "
          f"Monte Carlo: {m['runs']} runs, {m['kept_event_sequence']} kept the event sequence, {m['failed']} failed; "
          f"agree: {a['agree']}")
    for e in a["events"]:
        print(f"  event at t = {e['t']:.4f} s ({e['guards']}): conewise {e['conewise']}")
    traj = r["reference"]
    print(f"reference: {traj}")
