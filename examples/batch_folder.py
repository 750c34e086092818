"""Simulate every problem file of a folder in parallel and list what each found.

Run: python examples/batch_folder.py [PROBLEM_FOLDER] [OUT_FOLDER]
"""

from __future__ import annotations

import sys
from pathlib import Path

import casadi_posture as cp

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def main(
    folder: Path = PROBLEMS,
    out: Path = Path("out/examples/batch"),
    jobs: int = 2,
    overrides: dict | None = None,
) -> cp.BatchReport:
    report = cp.batch([folder], out, jobs=jobs, force=True, overrides=overrides)
    for row in report.rows:
        outcome = (
            f"held {'≥ ' if row.get('task_held_is_lower_bound') else ''}"
            f"{row.get('task_held_s', 0):.0f} s, {row.get('fatigue_recovery_cycles', 0)} cycles"
            if row["status"] in ("ok", "flagged")
            else row["error"]
        )
        print(f"{row['case']:24s} {row['status']:8s} {outcome}")
    return report


if __name__ == "__main__":
    args = sys.argv[1:]
    main(
        Path(args[0]) if args else PROBLEMS,
        Path(args[1]) if len(args) > 1 else Path("out/examples/batch"),
    )
