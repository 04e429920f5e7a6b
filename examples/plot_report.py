#!/usr/bin/env python3
"""Figures of the main job's report (examples/demo.sh): PNGs made with matplotlib and one offline
page, report/index.html, that shows them with a caption each and the flagships' summary tables.

    python3 examples/plot_report.py [REPORT_DIR] [--scene NAME ...]     (default: report/)

Reads what the example programs write into REPORT_DIR (trajectory_io.hpp's formats):
  <scene>.csv   the trajectory sampled in time: t, segment, mode, q0.., v0.., u0..
  <scene>.json  its segments and events (time, impact, guards with contact and kind, modes,
                impulses)
  <scene>_forces.csv   the contact forces along it (contact_forces_csv.hpp): t, segment, <contact>_n,
                <contact>_t0..
  plank_box_ocp.json   the plank-box pipeline's report (discovery, refinement, analysis)
  hopper_ocp.json      the hopper-over-three-holes pipeline's report (the same stages)
  hopper_gains.json    the hopper hop's jump gains per event
and writes REPORT_DIR/figures/*.png and REPORT_DIR/index.html. The scenes are the main job's unless
--scene names others (a user's own trajectory files, written by write_trajectory_files and
write_contact_forces_file): each gets its states and, when its forces file is there, its forces. A file that is missing leaves its
figure out (the page says which); a file that is there but malformed is an error naming it.
Geometry of the drawings: scenes/plank_box.hpp and scenes/hopper.hpp (their default parameters).
"""
import csv
import html
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402

SCENES = ["bouncing_ball", "guiding_example", "hopper", "spatial_box", "plank_box", "plank_box_refined",
          "hopper_refined"]
# scenes/plank_box.hpp: box 0.3 x 0.1 m, plank 1 m hinged at its left end (origin).
BOX_LENGTH, BOX_HEIGHT, PLANK_LENGTH = 0.3, 0.1, 1.0
# scenes/hopper.hpp: thigh and shank 0.2 m; scenes/hopper_holes.hpp: holes at 0.5, 1.5, 2.5.
THIGH, SHANK = 0.2, 0.2
HOLES, HOLE_HALF_WIDTH, HOLE_DEPTH = (0.5, 1.5, 2.5), 0.25, 0.1


def save(fig, figures, name):
    """Writes the figure to figures/name and returns name."""
    fig.tight_layout()
    fig.savefig(os.path.join(figures, name), dpi=110)
    plt.close(fig)
    return name


def load_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except json.JSONDecodeError as e:
        raise SystemExit(f"plot_report: {path} is not valid JSON ({e})")


def read_trajectory(report, scene):
    """(columns, rows as float lists except 'mode', events) of <scene>.csv/.json, or None."""
    path_csv = os.path.join(report, scene + ".csv")
    path_json = os.path.join(report, scene + ".json")
    if not (os.path.exists(path_csv) and os.path.exists(path_json)):
        return None
    with open(path_csv, newline="") as f:
        rows = list(csv.reader(f))
    if len(rows) < 2 or rows[0][:3] != ["t", "segment", "mode"]:
        raise ValueError(f"{path_csv}: expected a header t,segment,mode,... and samples")
    header = rows[0]
    columns = {name: [] for name in header}
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise ValueError(f"{path_csv}: line {line} has {len(row)} fields, the header {len(header)}")
        for name, value in zip(header, row):
            columns[name].append(value if name == "mode" else float(value))
    events = load_json(path_json).get("events", [])
    return columns, events


def event_label(event):
    guards = ", ".join(f'{g["kind"]} {g["contact"]}' for g in event.get("guards", []))
    return ("impact: " if event.get("impact") else "") + guards


def mark_events(ax, events, label=False):
    for e in events:
        ax.axvline(e["t"], color="0.5", lw=0.8, ls="--")
        if label:
            ax.annotate(event_label(e), (e["t"], 1.0), xycoords=("data", "axes fraction"), rotation=90,
                        fontsize=7, va="top", ha="right", color="0.3")


def plot_states(report, figures, scene, columns, events):
    """q, v and u against time, the events marked and named."""
    groups = [(prefix, sorted(k for k in columns if k[0] == prefix and k[1:].isdigit())) for prefix in "qvu"]
    groups = [(p, names) for p, names in groups if names]
    fig, axes = plt.subplots(len(groups), 1, sharex=True, figsize=(8, 2.4 * len(groups)))
    axes = axes if len(groups) > 1 else [axes]
    titles = {"q": "positions q", "v": "velocities v", "u": "inputs u"}
    for ax, (prefix, names) in zip(axes, groups):
        for name in names:
            ax.plot(columns["t"], columns[name], lw=1.2, label=name)
        mark_events(ax, events, label=(prefix == groups[0][0]))
        ax.set_ylabel(titles[prefix])
        ax.legend(fontsize=7, loc="upper right", ncol=len(names))
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{scene}: states and inputs (dashed: events)")
    name = save(fig, figures, f"{scene}_states.png")
    return name, f"{scene}: positions, velocities and inputs against time; dashed lines are the events ({len(events)}), named at the top."


def read_forces(report, scene):
    """Columns of <scene>_forces.csv as float lists, or None when the file is not there."""
    path = os.path.join(report, scene + "_forces.csv")
    if not os.path.exists(path):
        return None
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if len(rows) < 2 or rows[0][:2] != ["t", "segment"] or len(rows[0]) < 3:
        raise ValueError(f"{path}: expected a header t,segment,<contact>_n,... and samples")
    columns = {name: [] for name in rows[0]}
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(rows[0]):
            raise ValueError(f"{path}: line {line} has {len(row)} fields, the header {len(rows[0])}")
        for name, value in zip(rows[0], row):
            columns[name].append(float(value))
    return columns


def plot_forces(report, figures, scene, forces, events):
    """Contact forces against time (normal and tangential per contact) and the impulses as stems."""
    impulses = [(e["t"], i) for e in events for i in e.get("impulses", [])]
    fig, axes = plt.subplots(2 if impulses else 1, 1, sharex=True, figsize=(8, 5 if impulses else 3))
    axes = axes if impulses else [axes]
    for name in (k for k in forces if k not in ("t", "segment")):
        axes[0].plot(forces["t"], forces[name], lw=1.2, label=name + (" (normal)" if name.endswith("_n") else ""))
    mark_events(axes[0], events, label=True)
    axes[0].set_ylabel("contact force [N]")
    axes[0].legend(fontsize=7, loc="upper right")
    axes[0].grid(alpha=0.3)
    if impulses:
        for k, contact in enumerate(sorted({i["contact"] for _, i in impulses})):
            times = [t for t, i in impulses if i["contact"] == contact]
            values = [i["normal"] for _, i in impulses if i["contact"] == contact]
            axes[1].stem(times, values, linefmt=f"C{k}-", markerfmt=f"C{k}o", basefmt=" ",
                         label=f"{contact} normal impulse")
        axes[1].set_ylabel("impulse [N s]")
        axes[1].legend(fontsize=7, loc="upper right")
        axes[1].grid(alpha=0.3)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{scene}: contact forces" + (" and impulses" if impulses else ""))
    name = save(fig, figures, f"{scene}_forces.png")
    return name, (f"{scene}: the contact forces of the flow in each segment's mode (zero on open contacts)"
                  + (f"; below, the normal impulses of the {len(impulses)} impulse(s) at the impacts." if impulses else "."))


def snapshot_times(t, events, count=6):
    times = [t[0]] + [e["t"] for e in events] + [t[-1]]
    step = (t[-1] - t[0]) / max(count - 1, 1)
    times += [t[0] + k * step for k in range(count)]
    return sorted(set(round(x, 9) for x in times))


def sample_at(columns, time):
    t = columns["t"]
    k = min(range(len(t)), key=lambda i: abs(t[i] - time))
    return {name: values[k] for name, values in columns.items()}


def plot_plank_box(report, figures, scene, columns, events):
    """The box (centre, angle) and the plank (angle about its hinge) at the events and between."""
    fig, ax = plt.subplots(figsize=(8, 3.5))
    times = snapshot_times(columns["t"], events)
    cmap = plt.get_cmap("viridis")
    for k, time in enumerate(times):
        s = sample_at(columns, time)
        color = cmap(k / max(len(times) - 1, 1))
        x, y, theta, phi = s["q0"], s["q1"], s["q2"], s["q3"]
        ax.plot([0, PLANK_LENGTH * math.cos(phi)], [0, PLANK_LENGTH * math.sin(phi)], color=color, lw=2)
        corners = [(-1, -1), (1, -1), (1, 1), (-1, 1), (-1, -1)]
        c, sn = math.cos(theta), math.sin(theta)
        px = [x + c * a * BOX_LENGTH / 2 - sn * b * BOX_HEIGHT / 2 for a, b in corners]
        py = [y + sn * a * BOX_LENGTH / 2 + c * b * BOX_HEIGHT / 2 for a, b in corners]
        ax.plot(px, py, color=color, lw=1.2, label=f"t = {time:.3f} s")
    ax.plot([0], [0], "ko")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title(f"{scene}: box and plank poses (the hinge at the origin)")
    name = save(fig, figures, f"{scene}_motion.png")
    what = ("the refined optimal reference: landing flat, sliding and lifting off to the target" if scene.endswith("refined")
            else "the box lowered onto the compliant plank")
    return name, f"{scene}: {what}; the poses at the events and at even times."


def leg(s):
    x, z, hip, knee = s["q0"], s["q1"], s["q2"], s["q3"]
    kx, kz = x + THIGH * math.sin(hip), z - THIGH * math.cos(hip)
    fx, fz = kx + SHANK * math.sin(hip + knee), kz - SHANK * math.cos(hip + knee)
    return (x, z), (kx, kz), (fx, fz)


def plot_hopper(report, figures, columns, events, holes=False):
    """Hip, knee and foot paths, the leg drawn at the events (holes: the hopper over three holes)."""
    fig, ax = plt.subplots(figsize=(12 if holes else 8, 4.5))
    samples = [sample_at(columns, time) for time in columns["t"]]
    paths = list(zip(*[leg(s) for s in samples]))
    for path, name in zip(paths, ["hip", "knee", "foot"]):
        ax.plot([p[0] for p in path], [p[1] for p in path], lw=1, label=name)
    for k, e in enumerate(events):
        hip, knee, foot = leg(sample_at(columns, e["t"]))
        ax.plot([hip[0], knee[0], foot[0]], [hip[1], knee[1], foot[1]], "k-o", ms=3, lw=1.5)
        if not holes:  # a dozen events over 3 m: the leg drawings alone, the times are in the states figure
            ax.annotate(f'{e["t"]:.3f} s: {event_label(e)}', hip, fontsize=7, xytext=(8, 8 + 10 * k),
                        textcoords="offset points", arrowprops={"arrowstyle": "-", "color": "0.6"})
    xmin = min(p[0] for p in paths[2]) - 0.1
    xmax = max(p[0] for p in paths[0]) + 0.1
    ax.axhline(0.0, color="0.3", lw=1)
    if holes:
        for c in HOLES:
            xs = [c + HOLE_HALF_WIDTH * math.cos(a * math.pi / 50) for a in range(51)]
            ys = [-HOLE_DEPTH * math.sin(a * math.pi / 50) for a in range(51)]
            ax.fill(xs, ys, color="0.85")
    ax.set_xlim(xmin, xmax)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.legend(fontsize=7, loc="upper right")
    if holes:
        ax.set_title("hopper over three holes, refined reference: hip, knee and foot paths; the leg at each event")
        return save(fig, figures, "hopper_refined_motion.png"), (
            "hopper over three holes (T = 2.5 s, from rest at x = 0 to rest at x = 3): the refined optimal reference "
            "(discovery by the time-freezing homotopy, then the mode-schedule refinement); hip, knee and foot paths, "
            "the leg drawn at every touchdown and release, the holes shaded.")
    ax.set_title("hopper: hip, knee and foot paths; the leg at each event")
    return save(fig, figures, "hopper_motion.png"), "hopper: one hop (touchdown, stance, push-off); hip, knee and foot paths, the leg drawn at each event."


def plot_hopper_gains(report, figures):
    path = os.path.join(report, "hopper_gains.json")
    if not os.path.exists(path):
        return None
    events = load_json(path)["events"]
    fig, ax = plt.subplots(figsize=(6, 3))
    labels = [f'{e["guard"]}\nt = {e["t"]:.3f}' for e in events]
    ax.bar(labels, [max(e["G_z_minus_identity_max"], 1e-16) for e in events])
    ax.set_yscale("log")
    ax.set_ylabel("max |G_z - I|")
    ax.set_title("hopper hop: jump gain (saltation matrix) per event")
    return save(fig, figures, "hopper_jump_gains.png"), "hopper hop: the largest entry of G_z - I of each event's saltation matrix (the touchdown's impact dominates; a slip onset and a release without impact are continuous, ~1e-11)."


def plot_plank_box_analysis(report, figures):
    """The refined plank-box reference's jump gains and its tracking analysis."""
    path = os.path.join(report, "plank_box_ocp.json")
    if not os.path.exists(path):
        return [], None
    d = load_json(path)
    out = []
    a = d.get("analysis")
    if a and "events" in a:
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9, 3.2))
        labels = [f'{e["guards"]}\nt = {e["t"]:.3f}' for e in a["events"]]
        pieces = [e.get("pieces", 1) if e["conewise"] else 1 for e in a["events"]]
        colors = ["tab:orange" if e["conewise"] else "tab:blue" for e in a["events"]]
        ax1.bar(labels, pieces, color=colors)
        ax1.set_ylabel("linear pieces")
        ax1.set_title("jump gain per event (orange: conewise)")
        m = a.get("monte_carlo", {})
        keys = [k for k in ("runs", "kept_event_sequence", "shrank", "failed") if k in m]
        ax2.bar(keys, [m[k] for k in keys], color="tab:green")
        ax2.set_title(f'{a.get("design", "")}: {a.get("verdict", "")}, a(T) in [{a.get("lower_bound", float("nan")):.3g}, {a.get("upper_bound", float("nan")):.3g}]', fontsize=8)
        ax2.tick_params(axis="x", labelsize=7)
        out.append((save(fig, figures, "plank_box_analysis.png"),
                    "plank-box refined reference: the jump gain of each event (conewise at the simultaneous landing and lift-off, with its number of pieces), the tracking design's verdict with its bounds, and the Monte Carlo runs (kept the event sequence, shrank, failed)."))
    for figure in (plot_amplifications, plot_deviations):
        made = figure(figures, a) if a else None
        if made:
            out.append(made)
    return out, d


def plot_hopper_analysis(report, figures):
    """The refined hopper reference's jump gains and its Monte Carlo runs (hopper_ocp.json)."""
    path = os.path.join(report, "hopper_ocp.json")
    if not os.path.exists(path):
        return [], None
    d = load_json(path)
    a = d.get("analysis")
    if not a or "events" not in a:
        return [], d
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.4), gridspec_kw={"width_ratios": [2, 1]})
    labels = [f'{e["t"]:.3f}' for e in a["events"]]
    norms = [e.get("saltation_norm", float("nan")) for e in a["events"]]
    ax1.bar(labels, norms, color="tab:blue")
    ax1.set_yscale("log")
    ax1.set_xlabel("event time [s] (releases and touchdowns in turn)")
    ax1.set_ylabel("|G_z| (saltation matrix)")
    ax1.tick_params(axis="x", labelsize=7, rotation=45)
    ax1.set_title("jump gain per event")
    m = a.get("monte_carlo", {})
    keys = [k for k in ("runs", "kept_event_sequence", "shrank", "failed") if k in m]
    ax2.bar(keys, [m[k] for k in keys], color="tab:green")
    ax2.set_title(f'{a.get("verdict", "")}, a(T) = {a.get("upper_bound", float("nan")):.3g}; '
                  f'{"agrees" if a.get("agree") else "does not agree"}', fontsize=8)
    ax2.tick_params(axis="x", labelsize=7)
    caption = ("hopper over three holes, refined reference: the norm of each event's saltation matrix (about 1 at the "
               "releases, 30 to 1e5 at the touchdowns, where the stance's contact force meets the flight's free fall), "
               "and the LQR tracking design's Monte Carlo runs (kept the event sequence, shrank, failed) beside the "
               "stability check's verdict.")
    return [(save(fig, figures, "hopper_refined_analysis.png"), caption)], d


def finish(fig, ax, figures, name, xlabel, ylabel):
    """Labels, legend and log grid of a Monte Carlo figure; saves it as `name`."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, which="both")
    return save(fig, figures, name)


def plot_deviations(figures, analysis):
    """Each Monte Carlo run's deviation over time against its first-order prediction."""
    dev = analysis.get("monte_carlo", {}).get("deviations")
    if not dev or not dev.get("t") or not dev.get("observed"):
        return None
    t = dev["t"]
    kept = analysis["monte_carlo"]["amplifications"]["kept_event_sequence"]
    finite = lambda v: [x if isinstance(x, (int, float)) and x > 0 else float("nan") for x in v]
    fig, ax = plt.subplots(figsize=(7, 3.6))
    for predicted, observed, k in zip(dev["predicted"], dev["observed"], kept):
        ax.semilogy(t, finite(predicted), color="0.55", lw=0.5, ls="--")
        ax.semilogy(t, finite(observed), color="tab:green" if k else "tab:red", lw=0.6, alpha=0.6)
    for e in analysis.get("events", []):
        ax.axvline(e["t"], color="tab:blue", lw=0.6, ls=":")
    ax.plot([], [], color="tab:green", label="simulated, kept the event sequence")
    ax.plot([], [], color="tab:red", label="simulated, other events")
    ax.plot([], [], color="0.55", ls="--", label="first order (same deviation)")
    ax.plot([], [], color="tab:blue", ls=":", label="reference events")
    name = finish(fig, ax, figures, "plank_box_deviations.png", "t [s]", "|x(t) - x_ref(t)| / |eps d|")
    return name, ("plank-box tracking analysis: every Monte Carlo run's deviation from the reference over time "
                  "(relative to its initial deviation, the plant compared with the reference segment of its own "
                  "phase), against the first-order prediction of the same initial deviation (dashed); the "
                  "reference's events dotted.")


def plot_amplifications(figures, analysis):
    """Each Monte Carlo run's simulated amplification against its first-order prediction."""
    amp = analysis.get("monte_carlo", {}).get("amplifications")
    if not amp or not amp.get("predicted"):
        return None
    fig, ax = plt.subplots(figsize=(5, 4.2))
    kept = amp["kept_event_sequence"]
    for flag, colour, label in ((True, "tab:green", "kept the event sequence"), (False, "tab:red", "other events")):
        xs = [p for p, k in zip(amp["predicted"], kept) if k == flag]
        ys = [o for o, k in zip(amp["observed"], kept) if k == flag]
        if xs:
            ax.loglog(xs, ys, "o", ms=3, color=colour, label=f"{label} ({len(xs)})")
    lo = min(min(amp["predicted"]), min(amp["observed"]))
    hi = max(max(amp["predicted"]), max(amp["observed"]))
    ax.loglog([lo, hi], [lo, hi], color="0.4", lw=0.8, ls="--", label="simulated = first order")
    upper = analysis.get("upper_bound")
    if isinstance(upper, (int, float)):
        ax.axvline(upper, color="tab:blue", lw=0.8, label="stability check's upper bound")
    name = finish(fig, ax, figures, "plank_box_monte_carlo.png", "first-order amplification |z(T)| / |d|",
                  "simulated |x(T) - x_ref(T)| / |eps d|")
    return name, ("plank-box tracking analysis: each Monte Carlo run's simulated amplification of its initial "
                  "deviation at T against the first-order prediction of the same deviation (on the dashed line "
                  "they agree), and the stability check's upper bound a(T).")


def summary_rows(d):
    if d is None:
        return []
    r = d.get("refinement") or {}
    a = d.get("analysis") or {}
    rows = [("stage", d.get("stage", "")), ("schedule", d.get("schedule", "")),
            ("relaxed objective", d.get("relaxed_objective")), ("refined objective", r.get("objective")),
            ("mode validity", r.get("mode_validity_violation")), ("per-phase re-simulation", r.get("phase_resim_max_error")),
            ("open-loop re-simulation", (r.get("open_loop") or {}).get("max_error")),
            ("discovery [s]", d.get("discovery_seconds")), ("refinement [s]", r.get("refinement_seconds")),
            ("tracking verdict", a.get("verdict")), ("Monte Carlo agrees", a.get("agree"))]
    return [(k, v) for k, v in rows if v is not None]


def write_index(report, figures_made, missing, tables):
    def fmt(v):
        return f"{v:.4g}" if isinstance(v, float) else html.escape(str(v))
    parts = ["<!DOCTYPE html><html><head><meta charset='utf-8'><title>Saltus report</title>",
             "<style>body{font-family:sans-serif;max-width:60em;margin:auto}figure{margin:1.5em 0}"
             "img{max-width:100%}td,th{padding:2px 8px;border-bottom:1px solid #ddd;text-align:left}</style>",
             "</head><body><h1>Saltus: the main job's report</h1>"]
    for title, table in tables:
        if not table:
            continue
        parts.append(f"<h2>{html.escape(title)}: discovery, refinement, analysis</h2><table>")
        parts += [f"<tr><th>{html.escape(k)}</th><td>{fmt(v)}</td></tr>" for k, v in table]
        parts.append("</table>")
    parts.append("<h2>Figures</h2>")
    for name, caption in figures_made:
        parts.append(f"<figure><img src='figures/{name}' alt='{html.escape(name)}'>"
                     f"<figcaption>{html.escape(caption)}</figcaption></figure>")
    if missing:
        parts.append("<p>Not drawn (their files are not in the report): " + html.escape(", ".join(missing)) + "</p>")
    parts.append("</body></html>")
    with open(os.path.join(report, "index.html"), "w") as f:
        f.write("\n".join(parts))


def main(argv):
    args = argv[1:]
    scenes = SCENES
    if "--scene" in args:
        at = args.index("--scene")
        scenes = [a for a in args[at + 1:] if not a.startswith("--")]
        args = args[:at]
        if not scenes:
            raise SystemExit("plot_report: --scene needs at least one scene name")
    report = args[0] if args else "report"
    if not os.path.isdir(report):
        raise SystemExit(f"plot_report: {report} is not a directory (run examples/demo.sh first)")
    figures = os.path.join(report, "figures")
    os.makedirs(figures, exist_ok=True)
    made, missing = [], []
    for scene in scenes:
        data = read_trajectory(report, scene)
        if data is None:
            missing.append(scene)
            continue
        columns, events = data
        made.append(plot_states(report, figures, scene, columns, events))
        forces = read_forces(report, scene)
        if forces is not None:
            made.append(plot_forces(report, figures, scene, forces, events))
        if scene.startswith("plank_box"):
            made.append(plot_plank_box(report, figures, scene, columns, events))
        if scene == "hopper":
            made.append(plot_hopper(report, figures, columns, events))
        if scene == "hopper_refined":
            made.append(plot_hopper(report, figures, columns, events, holes=True))
    gains = plot_hopper_gains(report, figures)
    if gains:
        made.append(gains)
    analysis, plank = plot_plank_box_analysis(report, figures)
    made += analysis
    if plank is None:
        missing.append("plank_box_ocp.json")
    hopper_analysis, hopper = plot_hopper_analysis(report, figures)
    made += hopper_analysis
    write_index(report, made, missing, [("Plank-box flat landing", summary_rows(plank)),
                                        ("Hopper over three holes", summary_rows(hopper))])
    for name, _ in made:
        if not os.path.getsize(os.path.join(figures, name)) > 0:
            raise SystemExit(f"plot_report: {name} is empty")
    for scene in missing:
        if scene.endswith(".json"):
            continue
        print(f"plot_report: no figures of {scene}: {report} needs {scene}.csv and {scene}.json "
              "(saltus::write_trajectory_files writes both)", file=sys.stderr)
    print(f"plot_report: {len(made)} figures in {figures}, page {os.path.join(report, 'index.html')}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
