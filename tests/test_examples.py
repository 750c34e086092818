"""The examples run, small, so they never rot."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import pytest

import casadi_posture as cp

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _example(name: str):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_compare_solvers(capsys: pytest.CaptureFixture[str]) -> None:
    comparisons = _example("compare_solvers").main()
    assert comparisons and all(c.agree for c in comparisons)
    assert "holding_m45" in capsys.readouterr().out


def test_whatif_study(tmp_path: Path) -> None:
    table = _example("whatif_study").main(tmp_path / "w", masses_kg=(1.0, 5.0), duration_s=60)
    assert list(table["loads[0].mass_kg"]) == [1.0, 5.0]
    endurance = list(table["limiting_endurance_at_start_min"])
    assert endurance[1] < endurance[0]


def test_batch_folder(tmp_path: Path) -> None:
    report = _example("batch_folder").main(
        out=tmp_path / "b", jobs=1, overrides={"simulation.duration_s": 10.0}
    )
    statuses = {row["case"]: row["status"] for row in report.rows}
    without_tasks = {"frontal_elbow", "recorded_box_transfer"}  # a curve, a recording
    assert {statuses[c] for c in without_tasks} == {"skipped"}
    assert {s for c, s in statuses.items() if c not in without_tasks} == {"ok"}


def test_wall_protocol(capsys: pytest.CaptureFixture[str]) -> None:
    wall = _example("wall_protocol")
    problem = cp.load(wall.PROBLEMS / "standing_wall_horizontal.toml")
    height, distance = (float(v) for v in wall.wrist_position(problem)(problem.posture))
    # The file puts the dot 1.108625 m above the floor, 0.35 m ahead of and 0.25 m below
    # the shoulder's centre (the file's arm angles put the wrist there).
    assert height == pytest.approx(1.108625, abs=1e-6)
    assert distance == pytest.approx(math.hypot(0.35, 0.25), abs=1e-4)
    rows = wall.main(duration_s=60.0, lines=wall.LINES[:1], variants=wall.VARIANTS[:1])
    cells = [c.strip() for c in rows[0].strip("|").split("|")]
    # 60 s, before any group reaches the threshold: nothing recovers, the wrist is held.
    assert cells[2:5] == ["none", "0", "1 (whole run)"]
    assert "0.60 m from the shoulder" in rows[1]
    assert "wall time" in capsys.readouterr().out


def test_wall_protocol_merges_repeated_recoveries() -> None:
    wall = _example("wall_protocol")
    first, again = (
        wall.Recovery(364, 1.25, 0.22, -0.21, 0.0),
        wall.Recovery(681, 1.252, 0.221, -0.2, 0.0),
    )
    other = wall.Recovery(900, 1.30, 0.20, -0.25, 0.01)
    text = wall.positions_text([first, again, other])
    assert text == (
        "1.25 m, 0.22 m (-0.21 m along; 364, 681 s); "
        "1.30 m, 0.20 m (-0.25 m along, off the line 0.010 m; 900 s)"
    )
