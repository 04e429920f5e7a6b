#!/usr/bin/env python3
"""Figures of the main job's report (examples/demo.sh): PNGs made with matplotlib, each in its
scene's folder, and one offline page, REPORT_DIR/index.html, that shows them all with a one-line
caption each, the summary table of the pipelines and links into the folders.

    python3 examples/plot_report.py [REPORT_DIR] [--scene NAME ...]     (default: report/)

REPORT_DIR holds one folder per scene (examples/report_files.hpp, docs/report.md):
  <scene>/trajectory.csv    the trajectory sampled in time: t, segment, mode, q0.., v0.., u0..
  <scene>/trajectory.json   its segments and events (time, impact, guards with contact and kind,
                            modes, impulses)
  <scene>/forces.csv        the contact forces along it (write_contact_forces_csv): t, segment,
                            <contact>_n, <contact>_t0..
  <scene>/report.json       a pipeline's report: discovery, refinement and analysis of the
                            flagships (plank_box_flat_landing, hopper_over_three_holes), the
                            guiding example's time-freezing OCP, or the tracking designs' checks and
                            Monte Carlo batches (tracking_stability)
  <scene>/jump_gains.json   the hopper hop's jump gains per event
and this script writes each figure into its scene's folder (states.png, forces.png, motion.png,
jump_gains.png, analysis.png, monte_carlo.png, deviations.png, stability.png) and the page, then
checks them: every figure that the files present call for (expected_figures) must be drawn as a PNG
of its figsize x DPI pixels and shown on the page with a one-line caption, with a summary table of
each pipeline report; otherwise it exits with an error listing what is broken (ctest
example_plot_report, example_plot_report_flagships).
The scenes are the main job's unless --scene names others: a user's own folders, each with the
trajectory files (saltus::write_trajectory_files(scene, traj, "trajectory", dt, folder)) and, when
there, forces.csv (saltus::write_contact_forces_csv); each gets its states and its forces. A file
that is missing leaves its figure out (the page says which); a file that is there but malformed is
an error naming it.
Geometry of the drawings: scenes/plank_box.hpp and scenes/hopper.hpp (their default parameters).
"""
import csv
import html
import json
import math
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402

SCENES = ["bouncing_ball", "guiding_example", "plank_box", "hopper", "spatial_box", "plank_box_flat_landing",
          "hopper_over_three_holes", "tracking_stability"]
# Names on the page and in the captions (the folder name, underscores as spaces, otherwise).
TITLES = {"plank_box": "plank-box", "plank_box_flat_landing": "plank-box flat landing"}
# scenes/plank_box.hpp: box 0.3 x 0.1 m, plank 1 m hinged at its left end (origin).
BOX_LENGTH, BOX_HEIGHT, PLANK_LENGTH = 0.3, 0.1, 1.0
# scenes/hopper.hpp: thigh and shank 0.2 m; scenes/hopper_holes.hpp: holes at 0.5, 1.5, 2.5.
THIGH, SHANK = 0.2, 0.2
HOLES, HOLE_HALF_WIDTH, HOLE_DEPTH = (0.5, 1.5, 2.5), 0.25, 0.1
# The scenes whose motion is drawn: the drawing and its figsize [in].
MOTIONS = {"plank_box": ("plank box", (8, 3.5)), "plank_box_flat_landing": ("plank box", (8, 3.5)),
           "hopper": ("hopper", (8, 4.5)), "hopper_over_three_holes": ("hopper over holes", (12, 4.5))}
# figsize [in] of the figures of a fixed size (states_size, forces_size, tracking_size: the others).
SIZES = {"jump_gains": (6, 3), "analysis": (10, 3.4), "monte_carlo": (5, 4.2), "deviations": (8, 3.8)}

DPI = 110  # every figure: figsize [in] x DPI pixels (no tight bounding box), checked by check_report
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def title(scene):
    return TITLES.get(scene, scene.replace("_", " "))


def save(fig, report, scene, name):
    """Writes the figure to REPORT_DIR/scene/name and returns its path on the page, scene/name."""
    fig.tight_layout()
    fig.savefig(os.path.join(report, scene, name), dpi=DPI)
    plt.close(fig)
    return f"{scene}/{name}"


def states_size(columns):
    """figsize of states.png: one row per group of q, v and u columns."""
    return 8, 2.4 * sum(any(k[0] == p and k[1:].isdigit() for k in columns) for p in "qvu")


def forces_size(events):
    """figsize of forces.png: a second row for the impulses when an event has some."""
    return (8, 5) if any(e.get("impulses") for e in events) else (8, 3)


def tracking_size(cases):
    """figsize of stability.png: a row per design."""
    return 11, 1.4 + 0.42 * len(cases)


def load_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except json.JSONDecodeError as e:
        raise SystemExit(f"plot_report: {path} is not valid JSON ({e})")


def scene_json(report, scene, name):
    """REPORT_DIR/scene/name read as JSON, or None when the file is not there."""
    path = os.path.join(report, scene, name)
    return load_json(path) if os.path.exists(path) else None


def read_columns(path, first, text=()):
    """{column: values} of a CSV file whose header starts with `first`; floats except the `text` columns."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if len(rows) < 2 or rows[0][:len(first)] != first or len(rows[0]) <= len(first):
        raise ValueError(f"{path}: expected a header {','.join(first)},... and samples")
    header = rows[0]
    columns = {name: [] for name in header}
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise ValueError(f"{path}: line {line} has {len(row)} fields, the header {len(header)}")
        for name, value in zip(header, row):
            columns[name].append(value if name in text else float(value))
    return columns


def read_trajectory(report, scene):
    """(columns, events) of scene/trajectory.csv and trajectory.json, or None without both."""
    path_csv = os.path.join(report, scene, "trajectory.csv")
    path_json = os.path.join(report, scene, "trajectory.json")
    if not (os.path.exists(path_csv) and os.path.exists(path_json)):
        return None
    columns = read_columns(path_csv, ["t", "segment", "mode"], text=("mode",))
    return columns, load_json(path_json).get("events", [])


def read_forces(report, scene):
    """Columns of scene/forces.csv as float lists, or None when the file is not there."""
    path = os.path.join(report, scene, "forces.csv")
    return read_columns(path, ["t", "segment"]) if os.path.exists(path) else None


def event_label(event):
    guards = ", ".join(f'{g["kind"]} {g["contact"]}' for g in event.get("guards", []))
    return ("impact: " if event.get("impact") else "") + guards


def mark_events(ax, events, label=False):
    for e in events:
        ax.axvline(e["t"], color="0.5", lw=0.8, ls="--")
        if label:
            ax.annotate(event_label(e), (e["t"], 1.0), xycoords=("data", "axes fraction"), rotation=90,
                        fontsize=7, va="top", ha="right", color="0.3")


def plot_states(report, scene, columns, events):
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
    fig.suptitle(f"{title(scene)}: states and inputs (dashed: events)")
    return save(fig, report, scene, "states.png"), (
        f"{title(scene)}: positions, velocities and inputs against time; the dashed lines are its "
        f"{len(events)} events, named at the top.")


def plot_forces(report, scene, forces, events):
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
    fig.suptitle(f"{title(scene)}: contact forces" + (" and impulses" if impulses else ""))
    return save(fig, report, scene, "forces.png"), (
        f"{title(scene)}: the contact forces of the flow in each segment's mode (zero on open contacts)"
        + (f"; below, the normal impulses of its {len(impulses)} impulse(s) at the impacts." if impulses else "."))


def snapshot_times(t, events, count=6):
    times = [t[0]] + [e["t"] for e in events] + [t[-1]]
    step = (t[-1] - t[0]) / max(count - 1, 1)
    times += [t[0] + k * step for k in range(count)]
    return sorted(set(round(x, 9) for x in times))


def sample_at(columns, time):
    t = columns["t"]
    k = min(range(len(t)), key=lambda i: abs(t[i] - time))
    return {name: values[k] for name, values in columns.items()}


def plot_plank_box(report, scene, columns, events):
    """The box (centre, angle) and the plank (angle about its hinge) at the events and between."""
    fig, ax = plt.subplots(figsize=MOTIONS[scene][1])
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
    ax.set_title(f"{title(scene)}: box and plank poses (the hinge at the origin)")
    what = ("the refined optimal reference: landing flat, sliding and lifting off to the target"
            if scene == "plank_box_flat_landing" else "the box lowered onto the compliant plank")
    return save(fig, report, scene, "motion.png"), f"{title(scene)}: {what}; the poses at the events and at even times."


def leg(s):
    x, z, hip, knee = s["q0"], s["q1"], s["q2"], s["q3"]
    kx, kz = x + THIGH * math.sin(hip), z - THIGH * math.cos(hip)
    fx, fz = kx + SHANK * math.sin(hip + knee), kz - SHANK * math.cos(hip + knee)
    return (x, z), (kx, kz), (fx, fz)


def draw_holes(ax):
    for c in HOLES:
        xs = [c + HOLE_HALF_WIDTH * math.cos(a * math.pi / 50) for a in range(51)]
        ys = [-HOLE_DEPTH * math.sin(a * math.pi / 50) for a in range(51)]
        ax.fill(xs, ys, color="0.85")


def plot_hopper(report, scene, columns, events):
    """Hip, knee and foot paths, the leg drawn at the events (and the holes of the hopper over them)."""
    holes = MOTIONS[scene][0] == "hopper over holes"
    fig, ax = plt.subplots(figsize=MOTIONS[scene][1])
    paths = list(zip(*[leg(sample_at(columns, time)) for time in columns["t"]]))
    for path, name in zip(paths, ["hip", "knee", "foot"]):
        ax.plot([p[0] for p in path], [p[1] for p in path], lw=1, label=name)
    for k, e in enumerate(events):
        hip, knee, foot = leg(sample_at(columns, e["t"]))
        ax.plot([hip[0], knee[0], foot[0]], [hip[1], knee[1], foot[1]], "k-o", ms=3, lw=1.5)
        if not holes:  # a dozen events over 3 m: the leg drawings alone, the times are in the states figure
            ax.annotate(f'{e["t"]:.3f} s: {event_label(e)}', hip, fontsize=7, xytext=(8, 8 + 10 * k),
                        textcoords="offset points", arrowprops={"arrowstyle": "-", "color": "0.6"})
    ax.axhline(0.0, color="0.3", lw=1)
    if holes:
        draw_holes(ax)
    ax.set_xlim(min(p[0] for p in paths[2]) - 0.1, max(p[0] for p in paths[0]) + 0.1)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.legend(fontsize=7, loc="upper right")
    if holes:
        ax.set_title("hopper over three holes, refined reference: hip, knee and foot paths; the leg at each event")
        return save(fig, report, scene, "motion.png"), (
            "hopper over three holes (T = 2.5 s, from rest at x = 0 to rest at x = 3): the refined optimal reference; "
            "hip, knee and foot paths, the leg drawn at every touchdown and release, the holes shaded.")
    ax.set_title("hopper: hip, knee and foot paths; the leg at each event")
    return save(fig, report, scene, "motion.png"), (
        "hopper: one hop (touchdown, stance, push-off); hip, knee and foot paths, the leg drawn at each event.")


def plot_jump_gains(report, scene, gains):
    """jump_gains.json (the hopper hop's): the largest entry of G_z - I per event."""
    events = gains["events"]
    fig, ax = plt.subplots(figsize=SIZES["jump_gains"])
    labels = [f'{e["guard"]}\nt = {e["t"]:.3f}' for e in events]
    ax.bar(labels, [max(e["G_z_minus_identity_max"], 1e-16) for e in events])
    ax.set_yscale("log")
    ax.set_ylabel("max |G_z - I|")
    ax.set_title(f"{title(scene)}: jump gain (saltation matrix) per event")
    return save(fig, report, scene, "jump_gains.png"), (
        f"{title(scene)}: the largest entry of G_z - I of each event's closed-loop saltation matrix (an impact "
        "dominates; a slip onset or a release without impact is continuous, about 1e-11).")


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


def number(x):
    return x if isinstance(x, (int, float)) else math.nan


def event_norms(e, where):
    """[|G_z|_2] of a linear event; of a conewise event, one norm per piece (its piece_norms)."""
    if not e.get("conewise"):
        return [number(e.get("saltation_norm"))]
    norms = e.get("piece_norms")
    if not isinstance(norms, list) or len(norms) != e.get("pieces"):
        raise ValueError(f'{where}: the conewise event at t = {e["t"]} has no piece_norms for its '
                         f'{e.get("pieces")} pieces (one |G_z| per piece, reference_analysis_io.hpp)')
    return [number(n) for n in norms]


def gain_bars(ax, events, names, where):
    """Per event a bar of its |G_z|; at a conewise event one bar per piece, side by side."""
    for i, e in enumerate(events):
        norms = event_norms(e, where)
        width = 0.7 / len(norms)
        xs = [i - 0.35 + width * (k + 0.5) for k in range(len(norms))]
        bars = ax.bar(xs, norms, width=0.9 * width, color="tab:orange" if e.get("conewise") else "tab:blue")
        ax.bar_label(bars, [f"{n:.3g}" if len(norms) == 1 else f"#{k + 1}: {n:.5g}" for k, n in enumerate(norms)],
                     fontsize=6 if len(norms) > 1 else 7,
                     rotation=90 if len(norms) > 3 else 0)
    labels = [f'{e["t"]:.3f} s\n{name}' + (f'\n{e["pieces"]} pieces' if e.get("conewise") else "")
              for e, name in zip(events, names)]
    ax.set_xticks(range(len(events)), labels)
    ax.set_yscale("log")
    finite = [n for e in events for n in event_norms(e, where) if n == n and n > 0]
    ax.set_ylim(top=10 * max(finite or [1.0]))  # room for the labels
    ax.set_ylabel("|G_z|_2")
    ax.tick_params(axis="x", labelsize=7, rotation=45 if len(events) > 4 else 0)
    ax.set_title("jump gain per event" + (" (orange: a conewise gain, one bar per piece)"
                                          if any(e.get("conewise") for e in events) else ""), fontsize=9)


def conewise_summary(events, names):
    """'the 2 x touchdown event at 0.111 s: 2 pieces, |G_z| 3.246 and 3.2461': the conewise events' pieces."""
    parts = []
    for e, name in zip(events, names):
        if e.get("conewise"):
            norms = " and ".join(f"{n:.5g}" for n in event_norms(e, "analysis"))
            parts.append(f'the {name} event at {e["t"]:.3f} s: {e["pieces"]} pieces, |G_z| {norms}')
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


def plot_analysis(report, scene, a, trajectory_events):
    """Each event's jump gain (|G_z|, or the norm of each piece of a conewise gain) and the Monte Carlo runs."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=SIZES["analysis"], gridspec_kw={"width_ratios": [2, 1]})
    events = a["events"]
    names = [event_name(e, trajectory_events) for e in events]
    gain_bars(ax1, events, names, os.path.join(report, scene, "report.json"))
    monte_carlo_counts(ax2, a)
    fig.suptitle(f"{title(scene)}, refined reference: jump gains and tracking analysis", fontsize=10)
    conewise = conewise_summary(events, names)
    caption = (f"{title(scene)}, refined reference: the norm |G_z|_2 of each event's saltation matrix "
               f"({norm_ranges(events, names)})"
               + (f", and at a simultaneous event one bar per piece of its conewise gain ({conewise})"
                  if conewise else "")
               + "; right, the tracking design's Monte Carlo runs under the stability check's verdict and bounds "
               "on a(T).")
    return save(fig, report, scene, "analysis.png"), caption


def finish(fig, ax, report, scene, name, xlabel, ylabel):
    """Labels, legend and log grid of a Monte Carlo figure; saves it as scene/name."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(alpha=0.3, which="both")
    return save(fig, report, scene, name)


def positive(values):
    return [x if isinstance(x, (int, float)) and x > 0 else math.nan for x in values]


def plot_deviations(report, scene, analysis):
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
    ax.set_title(f"{title(scene)}: Monte Carlo deviations over time ({len(dev['observed'])} runs)", fontsize=9)
    nominal = analysis["monte_carlo"].get("relative_to_nominal_run", False)
    ylabel = "|e(t) - e_0(t)| / |eps d|,  e = x - x_ref" if nominal else "|x(t) - x_ref(t)| / |eps d|"
    name = finish(fig, ax, report, scene, "deviations.png", "t [s]", ylabel)
    against = " less the nominal closed-loop run's own error" if nominal else ""
    return name, (f"{title(scene)} tracking analysis: each Monte Carlo run's deviation from the reference over time "
                  f"(relative to its initial deviation{against}) against the first-order prediction of the same "
                  "deviation (dashed), with the stability check's bound a(T) and its peak over time.")


def plot_amplifications(report, scene, analysis):
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
    ax.set_title(f"{title(scene)}: amplification at T", fontsize=9)
    ax.legend(fontsize=7)
    ax.set_xlabel("first-order amplification |z(T)| / |d|")
    nominal = analysis["monte_carlo"].get("relative_to_nominal_run", False)
    ax.set_ylabel("simulated |e(T) - e_0(T)| / |eps d|" if nominal else "simulated |x(T) - x_ref(T)| / |eps d|")
    ax.grid(alpha=0.3, which="both")
    return save(fig, report, scene, "monte_carlo.png"), (
        f"{title(scene)} tracking analysis: each Monte Carlo run's simulated amplification of its initial deviation "
        "at T against the first-order prediction (on the dashed line they agree), and the stability check's upper "
        "bound a(T).")


def plot_pipeline(report, scene, d, trajectory_events):
    """The figures of a pipeline report's analysis (report.json's "analysis"), none without one."""
    a = d.get("analysis")
    if not a or "events" not in a:
        return []
    made = [plot_analysis(report, scene, a, trajectory_events)]
    return made + [m for m in (plot_amplifications(report, scene, a), plot_deviations(report, scene, a)) if m]


def plot_tracking_stability(report, scene, cases):
    """tracking_stability/report.json: per design the stability check's bounds and the Monte Carlo rates."""
    fig, (ax1, ax2) = plt.subplots(1, 2, sharey=True, figsize=tracking_size(cases))
    rows = list(range(len(cases)))[::-1]
    for y, c in zip(rows, cases):
        colour = "tab:green" if c["verdict"] == "stable" else "tab:red"
        lo, hi = c.get("lower_bound"), c.get("upper_bound")
        if isinstance(lo, (int, float)) and isinstance(hi, (int, float)) and lo > 0:
            ax1.plot([lo, hi], [y, y], "-", color=colour, lw=3)
            ax1.plot([hi], [y], "s" if "period" in c else "o", color=colour, ms=6)
        for key, style in (("predicted_rate", {"marker": "o", "mfc": "none", "color": colour, "ms": 7}),
                           ("observed_rate", {"marker": "x", "color": "k", "ms": 6})):
            ax2.plot([number(c.get(key))], [y], ls="none", **style)
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
    return save(fig, report, scene, "stability.png"), (
        "tracking designs along references with impacts: per design the stability check's bounds on a(T) or on the "
        "periodic hop's monodromy (below 1 is stable), and its predicted growth rate against the largest rate of the "
        "nonlinear closed-loop runs, with how many kept the event sequence.")


def summary_rows(d):
    """(key, value) rows of a pipeline report's table: discovery, refinement and analysis."""
    r = d.get("refinement") or {}
    a = d.get("analysis") or {}
    rows = [("stage", d.get("stage", "")), ("schedule", d.get("schedule", "")),
            ("relaxed objective", d.get("relaxed_objective")), ("refined objective", r.get("objective")),
            ("mode validity", r.get("mode_validity_violation")),
            ("per-phase re-simulation", r.get("phase_resim_max_error")),
            ("open-loop re-simulation", (r.get("open_loop") or {}).get("max_error")),
            ("discovery [s]", d.get("discovery_seconds")), ("refinement [s]", r.get("refinement_seconds")),
            ("tracking verdict", a.get("verdict")), ("Monte Carlo agrees", a.get("agree"))]
    return [(k, v) for k, v in rows if v is not None]


def overview_row(scene, d):
    """One row of the page's summary table: a pipeline report's stage, objective, events, verdict, seconds."""
    r, a = d.get("refinement") or {}, d.get("analysis") or {}
    m = a.get("monte_carlo") or {}
    events = len(r.get("event_times") or []) if r else len(d.get("events", []))
    agree = "agree" if a.get("agree") else "no agreement"
    mc = f'{m.get("kept_event_sequence", "?")}/{m.get("runs", "?")} kept, {agree}' if m else ""
    seconds = (d.get("discovery_seconds") or 0) + (r.get("refinement_seconds") or 0)
    return (f"<a href='#{scene}'>{html.escape(title(scene))}</a>", d.get("stage", ""), d.get("objective"), events,
            a.get("verdict", ""), mc, seconds)


def is_pipeline(d):
    return isinstance(d, dict) and "stage" in d


def table_heading(scene):
    return f"<h3>{html.escape(title(scene)[0].upper() + title(scene)[1:])}: the pipeline's summary</h3><table>"


def draw_folder(report, scene):
    """The figures of one scene's folder from the files in it, and its report.json (None without one)."""
    made, events = [], []
    data = read_trajectory(report, scene)
    if data is not None:
        columns, events = data
        made.append(plot_states(report, scene, columns, events))
        forces = read_forces(report, scene)
        if forces is not None:
            made.append(plot_forces(report, scene, forces, events))
        if scene in MOTIONS:
            draw = plot_plank_box if MOTIONS[scene][0] == "plank box" else plot_hopper
            made.append(draw(report, scene, columns, events))
    gains = scene_json(report, scene, "jump_gains.json")
    if gains is not None:
        made.append(plot_jump_gains(report, scene, gains))
    d = scene_json(report, scene, "report.json")
    if isinstance(d, dict) and "cases" in d:
        made.append(plot_tracking_stability(report, scene, d["cases"]))
    elif isinstance(d, dict):
        made += plot_pipeline(report, scene, d, events)
    return made, d


def expected_in_folder(report, scene):
    """{figure: figsize [in]} that draw_folder must draw from the files in scene's folder (its own reading)."""
    out = {}
    data = read_trajectory(report, scene)
    if data is not None:
        columns, events = data
        out["states.png"] = states_size(columns)
        if os.path.exists(os.path.join(report, scene, "forces.csv")):
            out["forces.png"] = forces_size(events)
        if scene in MOTIONS:
            out["motion.png"] = MOTIONS[scene][1]
    if os.path.exists(os.path.join(report, scene, "jump_gains.json")):
        out["jump_gains.png"] = SIZES["jump_gains"]
    d = scene_json(report, scene, "report.json")
    if isinstance(d, dict) and "cases" in d:
        out["stability.png"] = tracking_size(d["cases"])
    a = (d.get("analysis") or {}) if isinstance(d, dict) else {}
    m = a.get("monte_carlo") or {}
    if "events" in a:
        out["analysis.png"] = SIZES["analysis"]
        if (m.get("amplifications") or {}).get("predicted"):
            out["monte_carlo.png"] = SIZES["monte_carlo"]
        if (m.get("deviations") or {}).get("t") and m["deviations"].get("observed"):
            out["deviations.png"] = SIZES["deviations"]
    return out


def expected_figures(report, scenes):
    """{scene/figure: figsize [in]} that main must draw from the files present in report."""
    return {f"{scene}/{name}": size for scene in scenes for name, size in expected_in_folder(report, scene).items()}


def fmt(v):
    return "" if v is None else f"{v:.4g}" if isinstance(v, float) else html.escape(str(v))


def overview_table(rows):
    """The page's summary table: one row per pipeline report (overview_row)."""
    header = ("scene", "stage", "objective", "events", "verdict", "Monte Carlo", "discovery + refinement [s]")
    parts = ["<h2>Summary</h2><table>", "<tr>" + "".join(f"<th>{h}</th>" for h in header) + "</tr>"]
    for row in rows:
        cells = [row[0]] + [fmt(v) if k != 6 else f"{v:.0f}" for k, v in enumerate(row) if k > 0]
        parts.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    return parts + ["</table>"]


def figure_html(path, caption):
    """A figure on the page: the image and its one-line caption."""
    one_line = html.escape(" ".join(caption.split()))
    return f"<figure><img src='{path}' alt='{html.escape(path)}'><figcaption>{one_line}</figcaption></figure>"


def scene_section(report, scene, made, d):
    """A scene's section of the page: links to its folder's files, its pipeline's table, its figures."""
    files = sorted(f for f in os.listdir(os.path.join(report, scene)) if not f.endswith(".png"))
    links = ", ".join(f"<a href='{scene}/{html.escape(f)}'>{html.escape(f)}</a>" for f in files)
    parts = [f"<section id='{scene}'><h2>{html.escape(title(scene))}</h2>",
             f"<p>Folder <a href='{scene}/'>{scene}/</a>: {links}</p>"]
    if is_pipeline(d):
        parts.append(table_heading(scene))
        parts += [f"<tr><th>{html.escape(k)}</th><td>{fmt(v)}</td></tr>" for k, v in summary_rows(d)]
        parts.append("</table>")
    parts += [figure_html(path, caption) for path, caption in made]
    return parts + ["</section>"]


def write_index(report, sections, missing):
    """REPORT_DIR/index.html from sections [(scene, figures, report.json)] and the scenes not drawn."""
    parts = ["<!DOCTYPE html><html><head><meta charset='utf-8'><title>Saltus report</title>",
             "<style>body{font-family:sans-serif;max-width:60em;margin:auto}figure{margin:1.5em 0}"
             "img{max-width:100%}td,th{padding:2px 8px;border-bottom:1px solid #ddd;text-align:left}</style>",
             "</head><body><h1>Saltus: the main job's report</h1>",
             "<p>One folder per scene beside this page: its trajectory (trajectory.csv, trajectory.json), its "
             "contact forces (forces.csv), its pipeline's report (report.json) and its figures.</p>"]
    overview = [overview_row(scene, d) for scene, _, d in sections if is_pipeline(d)]
    if overview:
        parts += overview_table(overview)
    links = (f"<a href='#{s}'>{html.escape(title(s))}</a>" for s, _, _ in sections)
    parts.append("<p>Scenes: " + ", ".join(links) + "</p>")
    for scene, made, d in sections:
        parts += scene_section(report, scene, made, d)
    if missing:
        parts.append("<p>Not drawn (their files are not in the report): " + html.escape(", ".join(missing)) + "</p>")
    parts.append("</body></html>")
    with open(os.path.join(report, "index.html"), "w") as f:
        f.write("\n".join(parts))


def png_size(path):
    """(width, height) in pixels from the IHDR chunk of a PNG file, or an error message."""
    with open(path, "rb") as f:
        head = f.read(24)
    if len(head) < 24 or head[:8] != PNG_SIGNATURE or head[12:16] != b"IHDR":
        return f"{path} is not a PNG file (no PNG signature and IHDR chunk)"
    return int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")


def figure_problems(report, page, name, size):
    """What is wrong with one expected figure: its file (a PNG of size x DPI pixels, +-2) and its place on the page."""
    path = os.path.join(report, name)
    found = png_size(path) if os.path.exists(path) else f"{path} is missing"
    problems = [found] if isinstance(found, str) else []
    if not problems and (abs(found[0] - size[0] * DPI) > 2 or abs(found[1] - size[1] * DPI) > 2):
        problems.append(f"{path} is {found[0]} x {found[1]} px, expected {size[0] * DPI:.0f} x {size[1] * DPI:.0f}")
    shown = f"<img src='{re.escape(name)}'[^>]*><figcaption>[^<\n]*[^<\\s][^<\n]*</figcaption>"
    if page and not re.search(shown, page):
        problems.append(f"index.html does not show {name} with a one-line caption")
    return problems


def check_report(report, expected, scenes, drawn=None):
    """Problems (a list of messages) of the figures and REPORT_DIR/index.html against expected
    ({scene/figure: figsize}) and, when given, the names drawn: each figure a PNG of figsize x DPI
    pixels (+-2), shown on the page with a one-line caption; a summary table of each pipeline report
    in the scenes' folders, and the page's summary table."""
    problems = []
    if drawn is not None and set(drawn) != set(expected):
        problems.append(f"drawn {sorted(set(drawn) - set(expected))} not expected, "
                        f"expected {sorted(set(expected) - set(drawn))} not drawn")
    page_path = os.path.join(report, "index.html")
    page = open(page_path).read() if os.path.exists(page_path) else ""
    if not page:
        problems.append(f"{page_path} is missing or empty")
    for name, size in sorted(expected.items()):
        problems += figure_problems(report, page, name, size)
    pipelines = [s for s in scenes if is_pipeline(scene_json(report, s, "report.json"))]
    problems += [f"{page_path} has no summary table of {s}/report.json" for s in pipelines
                 if page and table_heading(s) not in page]
    if page and pipelines and "<h2>Summary</h2>" not in page:
        problems.append(f"{page_path} has no summary table of the pipelines")
    return problems


def parse_args(args):
    """(report directory, scenes) of the command line; --help prints the usage (the module docstring)."""
    if "--help" in args or "-h" in args:
        print(__doc__)
        raise SystemExit(0)
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
    return report, scenes


def main(argv):
    report, scenes = parse_args(argv[1:])
    sections, missing = [], []
    for scene in scenes:
        made, d = draw_folder(report, scene) if os.path.isdir(os.path.join(report, scene)) else ([], None)
        if made or d is not None:
            sections.append((scene, made, d))
        else:
            missing.append(scene)
            print(f"plot_report: no figures of {scene}: {os.path.join(report, scene)} has no trajectory "
                  "(trajectory.csv and trajectory.json, saltus::write_trajectory_files), report.json or "
                  "jump_gains.json", file=sys.stderr)
    if scenes is not SCENES and not sections:  # the user named scenes and none could be drawn
        raise SystemExit("plot_report: none of the scenes named by --scene could be drawn (above)")
    write_index(report, sections, missing)
    made = [name for _, figures, _ in sections for name, _ in figures]
    problems = check_report(report, expected_figures(report, scenes), scenes, made)
    if problems:
        raise SystemExit("plot_report: broken report:\n  " + "\n  ".join(problems))
    print(f"plot_report: {len(made)} figures in the scene folders of {report} (each checked: PNG, size, caption), "
          f"page {os.path.join(report, 'index.html')}")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv))
    except ValueError as e:  # a malformed input file, named in the message
        raise SystemExit(f"plot_report: {e}")
