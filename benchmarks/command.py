"""Wall time of the whole `simulate` command on the largest body we ship (not a test).

Run: python benchmarks/command.py [--repeat R]

The 20-minute standing hold with 1 kg (standing_wall_horizontal.toml, 29 DOF, 1201 steps)
as a user runs it: a fresh process each time (its imports, the build, the run, the files,
the figures, report.html), R times per variant — the default (files written side by side
by one process per core, at most 4), ``--jobs 1``, ``--no-figures`` and
``--no-figures --no-report`` — the best and the median printed. Then, in this process,
where the time of one command goes: the imports (in a fresh interpreter), the run, the
drawing modules' imports (which the process forked before the run makes while it goes
on), and each file written one after the other (the CPU time the side-by-side writing
shares out).
Target (issue 24): at most 1.5 s for the whole command.
"""

from __future__ import annotations

import argparse
import importlib
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from casadi_posture.output.report import table

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
HOLD = [
    str(PROBLEMS / "standing_wall_horizontal.toml"),
    "--set",
    "loads[0].mass_kg=1",
    "--set",
    "simulation.duration_s=1200",
]
VARIANTS = {
    "default": [],
    "--jobs 1": ["--jobs", "1"],
    "--no-figures": ["--no-figures"],
    "--no-figures --no-report": ["--no-figures", "--no-report"],
}


def _seconds(command: list[str]) -> tuple[float, float]:
    """Wall time and CPU time (user and system, its worker processes' included) [s] of
    ``command`` in a fresh process; an error stops the benchmark."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime


def commands(repeat: int) -> list[list]:
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for name, extra in VARIANTS.items():
            out = ["--out", str(Path(folder) / "run"), "--force"]
            command = [sys.executable, "-m", "casadi_posture", "simulate", *HOLD, *out, *extra]
            times = [_seconds(command) for _ in range(repeat)]
            wall = [w for w, _ in times]
            rows.append([name, min(wall), statistics.median(wall), min(c for _, c in times)])
    return rows


#: The modules the process forked before the run imports while it goes on (run_files).
DRAWING = (
    "casadi_posture.output.arrow_columns",
    "casadi_posture.output.html_report",
    "casadi_posture.output.plots",
)


def phases() -> list[list]:
    """One command's parts one after the other: imports in a fresh interpreter (the
    garbage collector off, as the command's entry point has it), then the run and each
    file in this process."""
    as_the_console = "import gc; gc.disable(); import casadi_posture.cli"  # console.py
    imports = min(_seconds([sys.executable, "-c", as_the_console])[0] for _ in "abc")
    from casadi_posture import api
    from casadi_posture.output.html_report import write_report
    from casadi_posture.output.plots import simulation_figures
    from casadi_posture.output.results import write_results

    drawing = f"{as_the_console}; import {', '.join(DRAWING)}"
    drawn = min(_seconds([sys.executable, "-c", drawing])[0] for _ in "abc") - imports
    problem = api.load(HOLD[0], {"loads[0].mass_kg": 1.0, "simulation.duration_s": 1200.0})
    start = time.perf_counter()
    run = api.simulate(problem)
    rows = [["imports (a fresh interpreter, best of 3)", imports]]
    rows.append(["the run", time.perf_counter() - start])
    rows.append(["drawing modules' imports (forked process, during the run)", drawn])
    for name in DRAWING:  # imported, as in the forked process, before the files are timed
        importlib.import_module(name)
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder)
        start = time.perf_counter()
        write_results(run.result, out, command=[])
        rows.append(["tables (CSV, Parquet, JSON)", time.perf_counter() - start])
        for name, draw in simulation_figures(run.result, out).items():
            start = time.perf_counter()
            draw()
            rows.append([name, time.perf_counter() - start])
        start = time.perf_counter()
        write_report(run.result, out / "report.html")
        rows.append(["report.html", time.perf_counter() - start])
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="runs per variant")
    args = parser.parse_args()
    print("casadi-posture simulate, 20-minute standing hold (1 kg, 29 DOF), fresh processes:")
    headers = ["variant", "best wall (s)", "median wall (s)", "least CPU (s)"]
    print(table(headers, commands(args.repeat)))
    rows = phases()
    rows.append(["sum (one process, one after the other)", sum(r[1] for r in rows)])
    print("\nwhere one command's time goes (one after the other):")
    print(table(["part", "wall (s)"], rows))


if __name__ == "__main__":
    main()
