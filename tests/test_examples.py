"""The examples run, small, so they never rot."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

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
    assert statuses["frontal_elbow"] == "skipped"
    assert {s for c, s in statuses.items() if c != "frontal_elbow"} == {"ok"}
