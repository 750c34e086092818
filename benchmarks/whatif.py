"""Wall time of a 20-case what-if with 1 and with 2 jobs, measured in one run (not a test).

Run: python benchmarks/whatif.py

The grid: the -45° hold with five loads (1-5 kg) × two strategies × two line angles,
simulated with the lexicographic solver; each case writes its folder and figures.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from casadi_posture.output.report import table
from casadi_posture.runs.batch import run_batch
from casadi_posture.runs.whatif import grid

PROBLEM = str(Path(__file__).resolve().parents[1] / "problems" / "holding_m45.toml")
VARIES = [
    ("loads[0].mass_kg", [1.0, 2.0, 3.0, 4.0, 5.0]),
    ("fatigue.strategy", ["active", "passive"]),
    ("tasks[0].elevation_deg", [-25.0, -45.0]),
]


def main() -> None:
    cases = grid(PROBLEM, VARIES, solver="lexicographic", simulate=True)
    rows, summaries = [], []
    for jobs in (1, 2):
        with tempfile.TemporaryDirectory() as folder:
            start = time.perf_counter()
            report = run_batch(cases, Path(folder), jobs=jobs, quiet=True)
            wall = time.perf_counter() - start
            summaries.append(report.summary.read_bytes())
        rows.append([jobs, len(cases), wall, wall / len(cases), len(report.failed)])
    print(table(["jobs", "cases", "wall (s)", "per case (s)", "failed"], rows, digits=2))
    print(
        f"\nspeed-up with 2 jobs: {rows[0][2] / rows[1][2]:.2f}×; "
        f"summaries identical: {summaries[0] == summaries[1]}"
    )


if __name__ == "__main__":
    main()
