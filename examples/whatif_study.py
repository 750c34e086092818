"""How long can the -45° hold be kept with 1 to 5 kg, and which muscle group gives out?
A simulated what-if over the load, as a DataFrame (needs pandas).

Run: python examples/whatif_study.py [OUT_FOLDER]
"""

from __future__ import annotations

import sys
from pathlib import Path

import casadi_posture as cp

HOLD = Path(__file__).resolve().parents[1] / "problems" / "holding_m45.toml"


def prepare_study(masses_kg: list[float], duration_s: float) -> dict[str, list]:
    """The varied keys: the load, and one duration for every case."""
    return {"loads[0].mass_kg": masses_kg, "simulation.duration_s": [duration_s]}


def main(
    out: Path = Path("out/examples/whatif"),
    masses_kg: tuple[float, ...] = (1.0, 2.5, 5.0),
    duration_s: float = 900.0,
) -> object:
    report = cp.whatif(HOLD, prepare_study(list(masses_kg), duration_s), out, force=True)
    table = report.to_frame()[
        [
            "loads[0].mass_kg",
            "limiting_group_at_start",
            "limiting_endurance_at_start_min",
            "exhausted_group",
            "task_held_s",
            "task_held_is_lower_bound",
        ]
    ].sort_values("loads[0].mass_kg")
    print(table.to_string(index=False))
    return table


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/examples/whatif"))
