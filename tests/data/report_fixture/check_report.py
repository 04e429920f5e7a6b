#!/usr/bin/env python3
"""The ctest example_plot_report_flagships: copies the small report beside this script (report/,
one folder per scene, made by make_fixture.py from the main job's outputs) to a fresh WORK_DIR, runs
plot_report.py on it and checks every figure the inputs call for (a PNG of the size the script
sets, on the page with a one-line caption), the pipelines' summary tables in index.html, and that
the figures named by --require (SCENE/FIGURE.png) are among them.

    check_report.py PLOT_REPORT_PY WORK_DIR [--require SCENE/FIGURE.png ...]
"""
import os
import shutil
import subprocess
import sys


def main(argv):
    plot_report, work = argv[1], argv[2]
    required = argv[argv.index("--require") + 1:] if "--require" in argv else []
    shutil.rmtree(work, ignore_errors=True)
    shutil.copytree(os.path.join(os.path.dirname(os.path.abspath(__file__)), "report"), work)
    subprocess.run([sys.executable, plot_report, work], check=True)
    sys.path.insert(0, os.path.dirname(os.path.abspath(plot_report)))
    import plot_report as pr  # noqa: E402 (the plotter's own reading of what it must draw)
    expected = pr.expected_figures(work, pr.SCENES)
    problems = pr.check_report(work, expected, pr.SCENES)
    problems += [f"{name} is not among the figures expected from the fixture" for name in required
                 if name not in expected]
    if problems:
        print("check_report: " + "\n  ".join(problems), file=sys.stderr)
        return 1
    print(f"check_report: {len(expected)} figures and index.html checked in {work}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
