#!/usr/bin/env python3
"""Makes the small report of the ctest example_plot_report_flagships (a few dozen kB) from a real
main-job report: every second sample of the trajectory and force CSVs (the samples on either side
of an event kept), numbers to 7 significant digits, a dozen of the Monte Carlo runs of each
flagship's analysis, and the pipelines' reports without the keys plot_report.py does not read
(homotopy steps, solves, failure messages).

    python3 make_fixture.py REPORT_DIR [SCENE ...]     writes ./report/<SCENE>/ beside this script

REPORT_DIR holds what `bash examples/demo.sh` writes, one folder per scene: the flagship pipelines'
plank_box_flat_landing/ and hopper_over_three_holes/ (report.json, trajectory.csv, trajectory.json,
forces.csv) and tracking_stability/report.json. SCENE names the folders to remake (default: all
three; a folder that REPORT_DIR does not have is left as it is). The committed fixture was made from
the runs of the main job's two pipelines and of `build/examples/tracking_stability --json`.
"""
import csv
import json
import os
import sys

RUNS = 12  # Monte Carlo runs kept per flagship (kept and not kept the event sequence, in their order)


def rounded(x):
    if isinstance(x, float):
        return float(f"{x:.7g}")
    if isinstance(x, list):
        return [rounded(v) for v in x]
    if isinstance(x, dict):
        return {k: rounded(v) for k, v in x.items()}
    return x


def thin_csv(src, dst):
    with open(src, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    seg = header.index("segment")
    keep = [r for k, r in enumerate(body)
            if k % 2 == 0 or k == len(body) - 1 or body[k - 1][seg] != r[seg]
            or (k + 1 < len(body) and body[k + 1][seg] != r[seg])]
    with open(dst, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        for r in keep:
            w.writerow([v if name == "mode" else f"{float(v):.7g}" for name, v in zip(header, r)])


def thin_monte_carlo(m):
    amp, dev = m["amplifications"], m.get("deviations")
    kept = amp["kept_event_sequence"]
    picks = [k for k, flag in enumerate(kept) if not flag][: RUNS // 2]
    picks = sorted(picks + [k for k, flag in enumerate(kept) if flag][: RUNS - len(picks)])
    m["amplifications"] = {key: [amp[key][k] for k in picks] for key in amp}
    if dev:
        m["deviations"] = {"t": dev["t"], "predicted": [dev["predicted"][k] for k in picks],
                           "observed": [dev["observed"][k] for k in picks]}
    m["failure_reasons"] = m.get("failure_reasons", [])[:2]
    m["departures"] = m.get("departures", [])[:2]


def thin_ocp(src, dst):
    with open(src) as f:
        d = json.load(f)
    for key in ("steps", "recovered_events", "continuation"):
        d.pop(key, None)
    d.get("discovery", {}).pop("steps", None)
    r = d.get("refinement") or {}
    for key in ("solves", "extraction_notes", "mesh_rounds"):
        r.pop(key, None)
    a = d.get("analysis") or {}
    if "monte_carlo" in a:
        thin_monte_carlo(a["monte_carlo"])
    with open(dst, "w") as f:
        json.dump(rounded(d), f, indent=1)


def thin_pipeline(src, dst):
    """A flagship's folder: its report, trajectory and forces, thinned."""
    os.makedirs(dst, exist_ok=True)
    for name in ("trajectory.csv", "forces.csv"):
        thin_csv(os.path.join(src, name), os.path.join(dst, name))
    with open(os.path.join(src, "trajectory.json")) as f:
        trajectory = json.load(f)
    with open(os.path.join(dst, "trajectory.json"), "w") as f:
        json.dump(rounded(trajectory), f, indent=1)
    thin_ocp(os.path.join(src, "report.json"), os.path.join(dst, "report.json"))


def main(argv):
    src = argv[1]
    scenes = argv[2:] or ["plank_box_flat_landing", "hopper_over_three_holes", "tracking_stability"]
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "report")
    for scene in scenes:
        if not os.path.isdir(os.path.join(src, scene)):
            continue
        if scene == "tracking_stability":
            os.makedirs(os.path.join(out, scene), exist_ok=True)
            with open(os.path.join(src, scene, "report.json")) as f:
                t = json.load(f)
            with open(os.path.join(out, scene, "report.json"), "w") as f:
                json.dump(t, f, indent=1)
        else:
            thin_pipeline(os.path.join(src, scene), os.path.join(out, scene))
        print(f"wrote {os.path.join(out, scene)}")


if __name__ == "__main__":
    main(sys.argv)
