#!/usr/bin/env bash
# The main job: installs the Debian packages (if missing), builds the libraries, the scene library
# and the example programs it runs (not the tests, not the benchmarks: `bash bench/run.sh`), runs
# the example scenes, the flagship pipelines of the plank-box and of the hopper over three holes
# (discovery, refinement, analysis; the two side by side on two cores) and the tracking designs,
# prints the results and writes the report: one folder per scene, report/<scene>/, with its
# trajectory (trajectory.json, trajectory.csv), its contact forces (forces.csv), its pipeline's
# report (report.json) and its figures (*.png), and report/index.html, one page with all of them
# (docs/report.md lists the folders and files). One progress line per stage on stderr.
#   SALTUS_JOBS=N   parallel build jobs (default: nproc)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# ccache (when installed): paths relative to the clone and no working directory in the hash, so that
# a fresh clone at another path on the same machine hits the cache of an earlier one.
export CCACHE_BASEDIR="$here" CCACHE_NOHASHDIR=1
build="$here/build"
start=$(date +%s)
bash "$here/.ci/install-deps.sh"
bash "$here/.ci/configure.sh" "$here" "$build" -DCMAKE_BUILD_TYPE=Release
examples=(bouncing_ball guiding_example plank_box hopper spatial_box tracking_stability)
cmake --build "$build" -j "${SALTUS_JOBS:-$(nproc)}" --target "${examples[@]}"
echo "built in $(( $(date +%s) - start )) s"
export SALTUS_REPORT_DIR="$here/report"
report="$SALTUS_REPORT_DIR"
mkdir -p "$report"/{guiding_example,plank_box_flat_landing,hopper_over_three_holes,tracking_stability}
for example in bouncing_ball guiding_example plank_box hopper spatial_box; do
  echo
  "$build/examples/$example"
done
# The guiding example's time-freezing OCP (a few seconds): JSON on stdout, progress on stderr.
echo
echo "== guiding_example --json (time-freezing OCP) =="
OPENBLAS_NUM_THREADS=1 "$build/examples/guiding_example" --json | tee "$report/guiding_example/report.json"
# The flagship pipeline of the plank-box flat landing, one thread (progress lines on stderr):
# discovery by the time-freezing homotopy until its contact schedule settles, the mode-schedule
# refinement (the exact reference), its re-simulations, then the analysis of the refined reference
# (jump gains, an LQR tracking design, its stability check and 200 perturbed runs). About 3
# minutes. The hopper over three holes runs the same chain from the paper's initialisation
# (`build/examples/hopper --json`: discovery of its footholds, their refinement, the analysis with
# 200 runs; about 5 minutes) on the other core, beside it: its progress lines go to
# report/hopper_over_three_holes/progress.log (docs/refinement.md, "Hopper over three holes").
ocp_summary() {
  python3 - "$1" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
refined = d.get("refinement") is not None
print(f'{"relaxed (discovery): " if refined else ""}converged {d["converged"]}  complementarity {d["complementarity"]:.2e}'
      f'  path violation {d["max_path_violation"]:.2e}  target error {d["target_error"]:.2e}'
      f'  objective {d.get("relaxed_objective", d["objective"]):.4g}  Ipopt iterations {d["ipopt_iterations"]}'
      f'  {d["solve_seconds"]:.0f} s  ({d["message"]})')
if "stage" in d:
    print(f'stage: {d["stage"]}')
    if refined:
        r = d["refinement"]
        print(f'  schedule {d["schedule"]}; relaxed objective {d["relaxed_objective"]:.4f} -> refined {r["objective"]:.4f};'
              f' mode validity {r["mode_validity_violation"]:.1e}; per-phase re-simulation {r["phase_resim_max_error"]:.1e};'
              f' open loop {r["open_loop"]["max_error"]:.1e}; discovery {d["discovery_seconds"]:.0f} s, refinement {r["refinement_seconds"]:.0f} s')
for e in ([] if refined else d.get("recovered_events", [])):
    print(f'  event t = {e["t"]:.6f}: {"impact" if e["impact"] else "mode change"}, {", ".join(e["guards"])}'
          f'  ({e["mode_before"]} -> {e["mode_after"]})')
if d.get("resim_max_error") is not None:
    print(f'  event-driven re-simulation: {len(d["resim_events"])} events at '
          + ", ".join(f'{e["t"]:.6f}' for e in d["resim_events"])
          + f'; largest state distance {d["resim_max_error"]:.2e} at t = {d["resim_max_error_at"]["t"]:.4f}')
a = d.get("analysis")
if a is not None:
    if "failure" in a:
        print(f'  analysis of the reference failed at the {a["failed_at"]}: {a["failure"]}')
    else:
        for e in a["events"]:
            gain = (f'conewise gain, {e["pieces"]} pieces, |G_z| = ' + ", ".join(f"{n:.5g}" for n in e["piece_norms"])
                    if e["conewise"]
                    else f'saltation matrix, |G_z| = {e["saltation_norm"]:.5g}')
            print(f'  jump gain at t = {e["t"]:.6f} ({e["guards"]} guards): {gain}')
        m = a["monte_carlo"]
        print(f'  tracking ({a["design"]}): {a["verdict"]}, a(T) in [{a["lower_bound"]:.3g}, {a["upper_bound"]:.3g}];'
              f' {m["runs"]} perturbed closed-loop runs: {m["kept_event_sequence"]} kept the event sequence,'
              f' {m["shrank"]} shrank, {m["failed"]} failed; first-order discrepancy {m["max_log_discrepancy"]:.2e}'
              f'; {"agree" if a["agree"] else "DISAGREE"}')
PY
}
echo
echo "== hopper --json (over three holes: discovery, refinement, analysis), in the background =="
hopper_dir="$report/hopper_over_three_holes"
OPENBLAS_NUM_THREADS=1 "$build/examples/hopper" --json > "$hopper_dir/report.json" 2> "$hopper_dir/progress.log" &
hopper_job=$!
echo "progress: $hopper_dir/progress.log"
echo
echo "== plank_box --json (the flat landing: discovery, refinement, analysis) =="
plank_box_json="$report/plank_box_flat_landing/report.json"
OPENBLAS_NUM_THREADS=1 "$build/examples/plank_box" --json > "$plank_box_json" ||
  echo "plank_box --json: the reference is not refined (see $plank_box_json)"
echo "plank-box flat landing (the relaxed solution where discovery stopped, then the refinement):"
ocp_summary "$plank_box_json"
echo "wrote $plank_box_json"
echo
echo "== hopper over three holes (waiting for its chain) =="
wait "$hopper_job" || echo "hopper --json: the refined reference did not pass every check (the stage below says which)"
python3 - "$hopper_dir/report.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
r = d.get("refinement") or {}
print(f'stage: {d["stage"]}')
print(f'  relaxed objective {d["relaxed_objective"]:.4g} -> refined {d["objective"]:.4f}; footholds at x = {", ".join(f"{x:.3f}" for x in d.get("footholds", []))}')
if r:
    within = sum(p["max_error"] <= 1e-6 for p in r["phase_resimulation"])
    print(f'  mode validity {r["mode_validity_violation"]:.1e}; path rows {r["path_violation"]:.1e}; target {r["terminal_violation"]:.1e};'
          f' per-phase re-simulation {r["phase_resim_max_error"]:.1e} ({within} of {len(r["phase_resimulation"])} phases within 1e-6);'
          f' discovery {d["discovery_seconds"]:.0f} s, refinement {r["refinement_seconds"]:.0f} s')
a = d.get("analysis")
if a and "failure" not in a:
    m = a["monte_carlo"]
    print(f'  jump gains: ' + ", ".join(f'{e["saltation_norm"]:.3g}' if not e["conewise"]
                                        else "pieces " + "/".join(f"{n:.3g}" for n in e["piece_norms"]) for e in a["events"]))
    print(f'  tracking ({a["design"]}): {a["verdict"]}, a(T) in [{a["lower_bound"]:.3g}, {a["upper_bound"]:.3g}];'
          f' {m["runs"]} perturbed runs: {m["kept_event_sequence"]} kept the event sequence, {m["failed"]} failed;'
          f' {"agree" if a["agree"] else "DISAGREE"}')
PY
echo "wrote $hopper_dir/report.json"
# Tracking designs along references with impacts: the stability check against 200 nonlinear
# closed-loop runs per design on all cores (a minute; progress lines on stderr).
echo
echo "== tracking_stability =="
"$build/examples/tracking_stability" --json > "$report/tracking_stability/report.json" || {
  echo "tracking_stability: a check and its Monte Carlo batch disagree (see the JSON)"; exit 1; }
python3 - "$report/tracking_stability/report.json" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
for c in d["cases"]:
    print(f'{c["name"]:<26} {c["design"]:<34} {c["verdict"]:<9} bounds [{c["lower_bound"]}, {c["upper_bound"]}] '
          f'rate pred {c["predicted_rate"]} obs {c["observed_rate"]} kept {c["kept_event_sequence"]}/{c["runs"]} '
          f'agree {c["agree"]} check {c["seconds"]} s MC {c["monte_carlo_seconds"]} s')
s = d["parallel_speedup"]
print(f'Monte Carlo speed-up on {s["threads"]} threads: {s["speedup"]} ({s["one_thread_seconds"]} s -> {s["all_threads_seconds"]} s)')
PY
echo "wrote $report/tracking_stability/report.json"
# The figures and the page that shows them (Debian's python3 with python3-matplotlib); plot_report.py
# checks each figure it must draw (a PNG of its size, shown on the page) and fails on a broken one:
# the summary below is still printed, and the main job's exit status is then 1.
echo
echo "== figures =="
python=/usr/bin/python3
[ -x "$python" ] || python=python3
figures_status=0
"$python" "$here/examples/plot_report.py" "$report" || figures_status=$?
echo
echo "== summary =="
python3 - "$report" <<'PY'
import json, os, sys
rows = [("scene", "stage", "objective", "events", "verdict", "Monte Carlo", "seconds")]
for scene, name in (("plank_box_flat_landing", "plank-box flat landing"), ("hopper_over_three_holes", "hopper over three holes")):
    path = os.path.join(sys.argv[1], scene, "report.json")
    if not os.path.exists(path):
        rows.append((name, "no report", "", "", "", "", ""))
        continue
    d = json.load(open(path))
    r, a = d.get("refinement") or {}, d.get("analysis") or {}
    m = a.get("monte_carlo") or {}
    events = len((r.get("event_times") or [])) if r else len(d.get("events", []))
    mc = f'{m.get("kept_event_sequence", "?")}/{m.get("runs", "?")} kept, {"agree" if a.get("agree") else "no agreement"}' if m else ""
    seconds = (d.get("discovery_seconds") or 0) + (r.get("refinement_seconds") or 0)
    rows.append((name, d.get("stage", "")[:40], f'{d.get("objective", float("nan")):.4g}', str(events),
                 a.get("verdict", ""), mc, f"{seconds:.0f} (discovery + refinement)"))
widths = [max(len(str(row[k])) for row in rows) for k in range(len(rows[0]))]
for row in rows:
    print("  ".join(str(v).ljust(w) for v, w in zip(row, widths)))
PY
echo
echo "main job done in $(( $(date +%s) - start )) s; report in $report (one folder per scene), page $report/index.html"
[ "$figures_status" = 0 ] || { echo "the figures are broken (plot_report.py above)"; exit 1; }
