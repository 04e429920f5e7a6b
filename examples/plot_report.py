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
  tracking_stability.json   the tracking designs' stability checks and Monte Carlo batches
                       (build/examples/tracking_stability --json)
and writes REPORT_DIR/figures/*.png and REPORT_DIR/index.html, then checks them: every figure that
the files present call for (expected_figures) must be drawn as a PNG of its figsize x DPI pixels and
shown on the page with a caption, with each flagship's summary table; otherwise it exits with an
error listing what is broken (ctest example_plot_report, example_plot_report_flagships).
The scenes are the main job's unless --scene names others (a user's own trajectory files, written by
write_trajectory_files and write_contact_forces_file): each gets its states and, when its forces
file is there, its forces. A file that is missing leaves its figure out (the page says which); a
file that is there but malformed is an error naming it.
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
# The flagship pipelines' reports: file, prefix of their figures, name in captions and on the page.
FLAGSHIPS = [("plank_box_ocp.json", "plank_box", "plank-box flat landing"),
             ("hopper_ocp.json", "hopper_refined", "hopper over three holes")]
# figsize [in] of the figures of a fixed size (states_size, forces_size, tracking_size: the others).
SIZES = {"plank_box_motion": (8, 3.5), "hopper_motion": (8, 4.5), "hopper_refined_motion": (12, 4.5),
         "jump_gains": (6, 3), "analysis": (10, 3.4), "monte_carlo": (5, 4.2), "deviations": (8, 3.8)}


DPI = 110  # every figure: figsize [in] x DPI pixels (no tight bounding box), checked by check_report
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def save(fig, figures, name):
    """Writes the figure to figures/name and returns name."""
    fig.tight_layout()
    fig.savefig(os.path.join(figures, name), dpi=DPI)
    plt.close(fig)
    return name


def states_size(columns):
    """figsize of <scene>_states.png: one row per group of q, v and u columns."""
    return 8, 2.4 * sum(any(k[0] == p and k[1:].isdigit() for k in columns) for p in "qvu")


def forces_size(events):
    """figsize of <scene>_forces.png: a second row for the impulses when an event has some."""
    return (8, 5) if any(e.get("impulses") for e in events) else (8, 3)


def tracking_size(cases):
    """figsize of tracking_stability.png: a row per design."""
    return 11, 1.4 + 0.42 * len(cases)


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
    fig, axes = plt.subplots(len(groups), 1, sharex=True, figsize=states_size(columns))
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
    fig, axes = plt.subplots(2 if impulses else 1, 1, sharex=True, figsize=forces_size(events))
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
    fig, ax = plt.subplots(figsize=SIZES["plank_box_motion"])
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
    fig, ax = plt.subplots(figsize=SIZES["hopper_refined_motion" if holes else "hopper_motion"])
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
    fig, ax = plt.subplots(figsize=SIZES["jump_gains"])
    labels = [f'{e["guard"]}\nt = {e["t"]:.3f}' for e in events]
    ax.bar(labels, [max(e["G_z_minus_identity_max"], 1e-16) for e in events])
    ax.set_yscale("log")
    ax.set_ylabel("max |G_z - I|")
    ax.set_title("hopper hop: jump gain (saltation matrix) per event")
    return save(fig, figures, "hopper_jump_gains.png"), "hopper hop: the largest entry of G_z - I of each event's saltation matrix (the touchdown's impact dominates; a slip onset and a release without impact are continuous, ~1e-11)."


def event_name(e, trajectory_events):
    """'touchdown', '2 x release', ... of an analysis event, from the trajectory's event at its time."""
    near = [x for x in trajectory_events if abs(x["t"] - e["t"]) < 1e-6]
    kinds = [g["kind"] for g in near[0]["guards"]] if near else []
    if not kinds:
        return f'{e.get("guards", "?")} guard(s)'
    return kinds[0] if len(kinds) == 1 else f"{len(kinds)} x " + "/".join(sorted(set(kinds)))


def norm_ranges(events, names):
    """'1.03 to 1.12 at the 6 release events; ...': the saltation norms' range per kind of event."""
    parts = []
    for name in sorted(set(n for e, n in zip(events, names) if not e.get("conewise"))):
        norms = [e["saltation_norm"] for e, n in zip(events, names) if n == name and not e.get("conewise")]
        parts.append(f"{norms[0]:.3g} at the {name} event" if len(norms) == 1
                     else f"{min(norms):.3g} to {max(norms):.3g} at the {len(norms)} {name} events")
    return "; ".join(parts)


def monte_carlo_counts(ax, a):
    """Bars of the Monte Carlo runs under the design, its verdict and its bounds."""
    m = a.get("monte_carlo", {})
    keys = [(k, label) for k, label in (("runs", "runs"), ("kept_event_sequence", "kept events"),
                                        ("shrank", "shrank"), ("failed", "failed")) if k in m]
    bars = ax.bar([label for _, label in keys], [m[k] for k, _ in keys], color="tab:green")
    ax.bar_label(bars, fontsize=7)
    ax.set_ylabel("perturbed closed-loop runs")
    ax.set_title(f'{a.get("design", "")}\n{a.get("verdict", "")}, a(T) in [{a.get("lower_bound", math.nan):.3g}, '
                 f'{a.get("upper_bound", math.nan):.3g}]; {"agrees" if a.get("agree") else "does not agree"}',
                 fontsize=8)
    ax.tick_params(axis="x", labelsize=7)


def plot_analysis(figures, prefix, title, a, trajectory_events):
    """Each event's jump gain (|G_z|, or the pieces of a conewise gain) and the Monte Carlo runs."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=SIZES["analysis"], gridspec_kw={"width_ratios": [2, 1]})
    events = a["events"]
    conewise = [e for e in events if e.get("conewise")]
    names = [event_name(e, trajectory_events) for e in events]
    labels = [f'{e["t"]:.3f} s\n{name}' for e, name in zip(events, names)]
    norms = [1.0 if e.get("conewise") else e.get("saltation_norm") or math.nan for e in events]
    bars = ax1.bar(labels, norms, color=["tab:orange" if e.get("conewise") else "tab:blue" for e in events])
    ax1.bar_label(bars, [f'{e["pieces"]} pieces' if e.get("conewise") else f"{n:.3g}" for e, n in zip(events, norms)],
                  fontsize=7)
    ax1.set_yscale("log")
    ax1.set_ylim(top=10 * max(n for n in norms if n == n))  # room for the labels
    ax1.set_ylabel("|G_z| (saltation matrix)")
    ax1.tick_params(axis="x", labelsize=7, rotation=45 if len(events) > 4 else 0)
    ax1.set_title("jump gain per event" + (" (orange: conewise, its number of pieces)" if conewise else ""), fontsize=9)
    monte_carlo_counts(ax2, a)
    fig.suptitle(f"{title}, refined reference: jump gains and tracking analysis", fontsize=10)
    caption = (f"{title}, refined reference: the norm of each event's saltation matrix ({norm_ranges(events, names)})"
               + (" (a conewise event, a simultaneous impact or release, is drawn at 1 with its number of linear "
                  "pieces; the report gives no norm per piece)" if conewise else "")
               + "; the tracking design's Monte Carlo runs (kept the event sequence, shrank, failed) under the "
               "stability check's verdict and bounds on a(T).")
    return save(fig, figures, f"{prefix}_analysis.png"), caption


def finish(fig, ax, figures, name, xlabel, ylabel):
    """Labels, legend and log grid of a Monte Carlo figure; saves it as `name`."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(alpha=0.3, which="both")
    return save(fig, figures, name)


def positive(values):
    return [x if isinstance(x, (int, float)) and x > 0 else math.nan for x in values]


def plot_deviations(figures, prefix, title, analysis):
    """Each Monte Carlo run's deviation over time against its first-order prediction and the bounds."""
    dev = analysis.get("monte_carlo", {}).get("deviations")
    if not dev or not dev.get("t") or not dev.get("observed"):
        return None
    t = dev["t"]
    kept = analysis["monte_carlo"]["amplifications"]["kept_event_sequence"]
    fig, ax = plt.subplots(figsize=SIZES["deviations"])
    for predicted, observed, k in zip(dev["predicted"], dev["observed"], kept):
        ax.semilogy(t, positive(predicted), color="0.55", lw=0.5, ls="--")
        ax.semilogy(t, positive(observed), color="tab:green" if k else "tab:red", lw=0.6, alpha=0.6)
    for e in analysis.get("events", []):
        ax.axvline(e["t"], color="tab:blue", lw=0.6, ls=":")
    peak, upper = analysis.get("peak_amplification"), analysis.get("upper_bound")
    if isinstance(peak, (int, float)):
        ax.axhline(peak, color="tab:purple", lw=0.8, ls="-.", label=f"bound's peak over time ({peak:.3g})")
    if isinstance(upper, (int, float)):
        ax.plot([t[-1]], [upper], "D", color="tab:purple", ms=5, label=f"stability check's bound a(T) = {upper:.3g}")
    for flag, colour, label in ((True, "tab:green", "kept the event sequence"), (False, "tab:red", "other events")):
        if flag in kept:
            ax.plot([], [], color=colour, label=f"simulated, {label} ({kept.count(flag)})")
    ax.plot([], [], color="0.55", ls="--", label="first order (same deviation)")
    ax.plot([], [], color="tab:blue", ls=":", label="reference events")
    ax.set_title(f"{title}: Monte Carlo deviations over time ({len(dev['observed'])} runs)", fontsize=9)
    nominal = analysis["monte_carlo"].get("relative_to_nominal_run", False)
    ylabel = "|e(t) - e_0(t)| / |eps d|,  e = x - x_ref" if nominal else "|x(t) - x_ref(t)| / |eps d|"
    name = finish(fig, ax, figures, f"{prefix}_deviations.png", "t [s]", ylabel)
    against = (" less the nominal (unperturbed) closed-loop run's own error, which removes the reference's defect"
               if nominal else "")
    return name, (f"{title} tracking analysis: every Monte Carlo run's deviation from the reference over time "
                  "(relative to its initial deviation, the plant compared with the reference segment of its own "
                  f"phase{against}), against the first-order prediction of the same initial deviation (dashed); the "
                  "stability check's bound a(T) at the horizon and the peak of its bound over time; the "
                  "reference's events dotted.")


def plot_amplifications(figures, prefix, title, analysis):
    """Each Monte Carlo run's simulated amplification against its first-order prediction."""
    amp = analysis.get("monte_carlo", {}).get("amplifications")
    if not amp or not amp.get("predicted"):
        return None
    fig, ax = plt.subplots(figsize=SIZES["monte_carlo"])
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
    ax.set_title(f"{title}: amplification at T", fontsize=9)
    ax.legend(fontsize=7)
    ax.set_xlabel("first-order amplification |z(T)| / |d|")
    nominal = analysis["monte_carlo"].get("relative_to_nominal_run", False)
    ax.set_ylabel("simulated |e(T) - e_0(T)| / |eps d|" if nominal else "simulated |x(T) - x_ref(T)| / |eps d|")
    ax.grid(alpha=0.3, which="both")
    name = save(fig, figures, f"{prefix}_monte_carlo.png")
    return name, (f"{title} tracking analysis: each Monte Carlo run's simulated amplification of its initial "
                  "deviation at T against the first-order prediction of the same deviation (on the dashed line "
                  "they agree), and the stability check's upper bound a(T).")


def plot_flagship(report, figures, file, prefix, title):
    """The figures of a flagship pipeline's report (file) and the report, or ([], None) without it."""
    path = os.path.join(report, file)
    if not os.path.exists(path):
        return [], None
    d = load_json(path)
    a = d.get("analysis")
    if not a or "events" not in a:
        return [], d
    trajectory = read_trajectory(report, prefix if prefix.endswith("refined") else prefix + "_refined")
    made = [plot_analysis(figures, prefix, title, a, trajectory[1] if trajectory else [])]
    for figure in (plot_amplifications, plot_deviations):
        drawn = figure(figures, prefix, title, a)
        if drawn:
            made.append(drawn)
    return made, d


def plot_tracking_stability(report, figures):
    """tracking_stability.json: per design the stability check's bounds and the Monte Carlo rates."""
    path = os.path.join(report, "tracking_stability.json")
    if not os.path.exists(path):
        return None
    cases = load_json(path)["cases"]
    fig, (ax1, ax2) = plt.subplots(1, 2, sharey=True, figsize=tracking_size(cases))
    rows = list(range(len(cases)))[::-1]
    for y, c in zip(rows, cases):
        colour = "tab:green" if c["verdict"] == "stable" else "tab:red"
        periodic = "period" in c
        lo, hi = c.get("lower_bound"), c.get("upper_bound")
        if isinstance(lo, (int, float)) and isinstance(hi, (int, float)) and lo > 0:
            ax1.plot([lo, hi], [y, y], "-", color=colour, lw=3)
            ax1.plot([hi], [y], "s" if periodic else "o", color=colour, ms=6)
        for key, style in (("predicted_rate", {"marker": "o", "mfc": "none", "color": colour, "ms": 7}),
                           ("observed_rate", {"marker": "x", "color": "k", "ms": 6})):
            ax2.plot([c[key] if isinstance(c.get(key), (int, float)) else math.nan], [y], ls="none", **style)
        ax2.annotate(f'{c["kept_event_sequence"]}/{c["runs"]} kept, {"agree" if c["agree"] else "DISAGREE"}',
                     (1.01, y), xycoords=("axes fraction", "data"), fontsize=7, va="center")
    ax1.axvline(1.0, color="0.3", lw=0.8, ls="--")
    ax1.set_xscale("log")
    ax1.set_yticks(rows, [f'{c["name"]}: {c["design"]}' for c in cases], fontsize=7)
    ax1.set_xlabel("bound on a(T) (circles) or on the monodromy's spectral radius (squares)", fontsize=8)
    ax1.set_title("stability check (green: stable, red: unstable)", fontsize=9)
    ax2.axvline(0.0, color="0.3", lw=0.8, ls="--")
    ax2.set_xlabel("rate [1/s]: predicted (open), largest observed (x)", fontsize=8)
    ax2.set_title("Monte Carlo against the prediction", fontsize=9)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3, which="both", axis="x")
    caption = ("tracking designs along references with impacts (build/examples/tracking_stability): per design, the "
               "stability check's bounds (lower to upper; on a(T), the amplification over the horizon, or on the "
               "spectral radius of the periodic hop's monodromy; below 1 is stable), and the growth rate it predicts "
               "against the largest rate of the nonlinear closed-loop runs, with how many kept the event sequence.")
    return save(fig, figures, "tracking_stability.png"), caption


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


def table_heading(title):
    return f"<h2>{html.escape(title[0].upper() + title[1:])}: discovery, refinement, analysis</h2><table>"


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
        parts.append(table_heading(title))
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


def expected_figures(report, scenes):
    """{figure: figsize [in]} that main must draw from the inputs present in report (its own reading)."""
    out = {}
    for scene in scenes:
        data = read_trajectory(report, scene)
        if data is None:
            continue
        columns, events = data
        out[f"{scene}_states.png"] = states_size(columns)
        if os.path.exists(os.path.join(report, scene + "_forces.csv")):
            out[f"{scene}_forces.png"] = forces_size(events)
        if scene.startswith("plank_box"):
            out[f"{scene}_motion.png"] = SIZES["plank_box_motion"]
        if scene in ("hopper", "hopper_refined"):
            out[f"{scene}_motion.png"] = SIZES[f"{scene}_motion"]
    if os.path.exists(os.path.join(report, "hopper_gains.json")):
        out["hopper_jump_gains.png"] = SIZES["jump_gains"]
    for file, prefix, _ in FLAGSHIPS:
        path = os.path.join(report, file)
        a = (load_json(path).get("analysis") or {}) if os.path.exists(path) else {}
        m = a.get("monte_carlo") or {}
        if "events" in a:
            out[f"{prefix}_analysis.png"] = SIZES["analysis"]
            if (m.get("amplifications") or {}).get("predicted"):
                out[f"{prefix}_monte_carlo.png"] = SIZES["monte_carlo"]
            if (m.get("deviations") or {}).get("t") and m["deviations"].get("observed"):
                out[f"{prefix}_deviations.png"] = SIZES["deviations"]
    path = os.path.join(report, "tracking_stability.json")
    if os.path.exists(path):
        out["tracking_stability.png"] = tracking_size(load_json(path)["cases"])
    return out


def png_size(path):
    """(width, height) in pixels from the IHDR chunk of a PNG file, or an error message."""
    with open(path, "rb") as f:
        head = f.read(24)
    if len(head) < 24 or head[:8] != PNG_SIGNATURE or head[12:16] != b"IHDR":
        return f"{path} is not a PNG file (no PNG signature and IHDR chunk)"
    return int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")


def check_report(report, expected, drawn=None):
    """Problems (a list of messages) of report/figures and report/index.html against expected
    ({figure: figsize}) and, when given, the names drawn: each figure a PNG of figsize x DPI pixels
    (+-2), shown on the page with a caption; the summary table of each flagship report present."""
    problems = []
    if drawn is not None and set(drawn) != set(expected):
        problems.append(f"drawn {sorted(set(drawn) - set(expected))} not expected, "
                        f"expected {sorted(set(expected) - set(drawn))} not drawn")
    page_path = os.path.join(report, "index.html")
    page = open(page_path).read() if os.path.exists(page_path) else ""
    if not page:
        problems.append(f"{page_path} is missing or empty")
    for name, (w, h) in sorted(expected.items()):
        path = os.path.join(report, "figures", name)
        size = png_size(path) if os.path.exists(path) else f"{path} is missing"
        if isinstance(size, str):
            problems.append(size)
        elif abs(size[0] - w * DPI) > 2 or abs(size[1] - h * DPI) > 2:
            problems.append(f"{path} is {size[0]} x {size[1]} px, expected {w * DPI:.0f} x {h * DPI:.0f}")
        if page and f"<img src='figures/{name}'" not in page:
            problems.append(f"{page_path} does not show {name}")
    if page and page.count("<figcaption>") < len(expected):
        problems.append(f"{page_path} has {page.count('<figcaption>')} captions for {len(expected)} figures")
    problems += [f"{page_path} has no summary table of the {title}" for file, _, title in FLAGSHIPS
                 if page and os.path.exists(os.path.join(report, file)) and table_heading(title) not in page]
    return problems


def draw_scene(report, figures, scene, columns, events):
    """The figures of one trajectory: states, forces when its file is there, the motion."""
    made = [plot_states(report, figures, scene, columns, events)]
    forces = read_forces(report, scene)
    if forces is not None:
        made.append(plot_forces(report, figures, scene, forces, events))
    if scene.startswith("plank_box"):
        made.append(plot_plank_box(report, figures, scene, columns, events))
    if scene in ("hopper", "hopper_refined"):
        made.append(plot_hopper(report, figures, columns, events, holes=(scene == "hopper_refined")))
    return made


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
    made, missing, tables = [], [], []
    for scene in scenes:
        data = read_trajectory(report, scene)
        if data is None:
            missing.append(scene)
            continue
        made += draw_scene(report, figures, scene, *data)
    made += [m for m in (plot_hopper_gains(report, figures), plot_tracking_stability(report, figures)) if m]
    for file, prefix, title in FLAGSHIPS:
        drawn, d = plot_flagship(report, figures, file, prefix, title)
        made += drawn
        tables.append((title, summary_rows(d)))
        if d is None:
            missing.append(file)
    if not os.path.exists(os.path.join(report, "tracking_stability.json")):
        missing.append("tracking_stability.json")
    write_index(report, made, missing, tables)
    for scene in missing:
        if not scene.endswith(".json"):
            print(f"plot_report: no figures of {scene}: {report} needs {scene}.csv and {scene}.json "
                  "(saltus::write_trajectory_files writes both)", file=sys.stderr)
    problems = check_report(report, expected_figures(report, scenes), [name for name, _ in made])
    if problems:
        raise SystemExit("plot_report: broken report:\n  " + "\n  ".join(problems))
    print(f"plot_report: {len(made)} figures in {figures} (each checked: PNG, size), "
          f"page {os.path.join(report, 'index.html')}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
