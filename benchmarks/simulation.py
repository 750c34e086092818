"""Speed of the time simulation with each solver on the shipped scenarios (not a test).

Run: python benchmarks/simulation.py

Per scenario and solver: simulated time, the wall time of the first run in this process
(which builds the body's functions and the solver) and of a second run (which reuses
them, as a what-if grid or a duty-cycle search does), wall time per simulated minute, and
the share of wall time spent outside the IK solve (torques, fatigue, the constraint and
its goal angle, recording). Target: at most 20 % outside the IK; the standing 20-minute
hold in at most 0.3 s (issue 24), first run included: its first run with each solver is
also timed in a fresh process (best of 3), where nothing is built yet. Last, the largest body
we ship held for a full 20 minutes: the standing wall hold with 1 kg (with 2.5 kg the
elbow gives out before), two fatigue/recovery cycles; and with 2.5 kg on a work–rest
schedule (60 s on, 30 s off), which holds the 20 minutes without the constraint.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from casadi_posture.output.report import table
from casadi_posture.problem import load_problem
from casadi_posture.simulation import simulate

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


#: (row label, problem file, overrides)
STANDING_20_MIN = (
    "standing_wall_horizontal, 1 kg, 20 min",
    "standing_wall_horizontal.toml",
    {"loads[0].mass_kg": 1.0, "simulation.duration_s": 1200.0},
)
#: The same body holding 2.5 kg for 20 minutes on a work–rest schedule: 60 s on, 30 s off.
STANDING_20_MIN_WORK_REST = (
    "standing_wall_horizontal, 2.5 kg, 60 s on / 30 s off, 20 min",
    "standing_wall_horizontal.toml",
    {"simulation.duration_s": 1200.0, "schedule.t_on_s": 60.0, "schedule.t_off_s": 30.0},
)


def main() -> None:
    rows = []
    cases = [(p.stem, load_problem(p)) for p in sorted(PROBLEMS.glob("*.toml"))]
    for label, name, overrides in (STANDING_20_MIN, STANDING_20_MIN_WORK_REST):
        cases.append((label, load_problem(PROBLEMS / name, overrides)))
    for stem, problem in cases:
        if not problem.tasks:
            continue
        for solver in ("nullspace", "lexicographic"):
            first = simulate(problem, solver)
            result = simulate(problem, solver)
            simulated_min = result.timeline.time[-1] / 60
            rows.append(
                [
                    stem,
                    solver,
                    60 * simulated_min,
                    first.wall_time_s,
                    result.wall_time_s,
                    result.wall_time_s / max(simulated_min, 1e-9),
                    100 * (1 - result.ik_time_s / result.wall_time_s),
                    result.timeline.time.size,
                    result.ik_fallbacks,
                    result.ik_failures,
                ]
            )
    print(
        table(
            [
                "scenario",
                "solver",
                "simulated (s)",
                "first run (s)",
                "again (s)",
                "wall per simulated min (s)",
                "outside IK (%)",
                "steps",
                "steps by the other solver",
                "IK failures",
            ],
            rows,
            digits=2,
        )
    )


#: The 20-minute hold's first run in a fresh interpreter: the wall time of ``simulate``.
FRESH = """
import sys, time
from casadi_posture.problem import load_problem
from casadi_posture.simulation import simulate
problem = load_problem(sys.argv[1], {overrides!r})
start = time.perf_counter()
simulate(problem, sys.argv[2])
print(time.perf_counter() - start)
"""


def fresh_first_runs(repeat: int = 3) -> list[list]:
    """The 20-minute standing hold's first run with each solver, each in a fresh process
    (the build included; imports and reading the file not): the best of ``repeat``."""
    _, name, overrides = STANDING_20_MIN
    script = FRESH.format(overrides=overrides)
    rows = []
    for solver in ("nullspace", "lexicographic"):
        command = [sys.executable, "-c", script, str(PROBLEMS / name), solver]
        runs = [float(subprocess.check_output(command, text=True)) for _ in range(repeat)]
        rows.append([STANDING_20_MIN[0], solver, min(runs), max(runs)])
    return rows


if __name__ == "__main__":
    main()
    print("\nfirst run in a fresh process (nothing built yet), 3 processes per solver:")
    headers = ["scenario", "solver", "best first run (s)", "worst first run (s)"]
    print(table(headers, fresh_first_runs(), digits=3))
