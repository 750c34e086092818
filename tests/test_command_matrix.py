"""Every recovery law, endurance model and adjustment through every command that runs a hold
over time (simulate, whatif, batch, duty-cycle, population, evaluate, rerun): each runs to an
answer and writes its files, and the files say which law and model made them.

The paper's adjustment on the −45° holding arm, the whole-body one on the standing wall,
both cut short and in 5-s steps (the standing wall's shoulder flexors reach the threshold
within 260 s, so its adjustment acts)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

from casadi_posture.biomech.endurance import ENDURANCE_MODELS
from casadi_posture.biomech.fatigue import RECOVERY_LAWS
from casadi_posture.cli import main

#: Each adjustment's problem, cut short.
ADJUSTMENTS = {
    "paper": (PROBLEMS / "holding_m45.toml", 200.0),
    "whole_body": (PROBLEMS / "standing_wall_horizontal.toml", 260.0),
}
#: Every recovery law with each endurance model it uses (3cc_r has its own).
LAWS = [
    (law, endurance)
    for law in RECOVERY_LAWS
    for endurance in ([None] if law == "3cc_r" else ENDURANCE_MODELS)
]


def settings(law: str, endurance: str | None, adjustment: str) -> list[str]:
    """``--set`` options of a law, an endurance model and an adjustment, and the time."""
    duration = ADJUSTMENTS[adjustment][1]
    chosen = {
        "fatigue.recovery_law": law,
        "fatigue.adjustment": adjustment,
        "simulation.duration_s": duration,
        "simulation.time_step_s": 5.0,
    }
    if endurance is not None:
        chosen["fatigue.endurance"] = endurance
    return [arg for key, value in chosen.items() for arg in ("--set", f"{key}={value}")]


def cli(*args: str | Path) -> str:
    """The command's output, after checking it ran to an answer (flagged or not)."""
    done = CliRunner().invoke(main, [str(a) for a in args])
    output = done.output
    assert done.exit_code in (0, 1), output
    assert "internal error" not in output, output
    return output


def made_by(summary: Path, law: str, endurance: str | None) -> None:
    """summary.json names the law and the endurance model that made it (``None``: the
    body's default)."""
    data = json.loads(summary.read_text())
    assert data["recovery_law"]["recovery_law"] == law
    expected = "3cc_r" if law == "3cc_r" else endurance
    assert data["endurance_model"] == (expected or data["endurance_model"])


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[tuple[str, str], Path]:
    """``simulate`` with every figure and the page, per law (its default endurance) and
    adjustment: what evaluate and rerun start from."""
    made = {}
    for adjustment, (problem, _) in ADJUSTMENTS.items():
        for law in RECOVERY_LAWS:
            out = tmp_path_factory.mktemp(f"{law}-{adjustment}")
            cli("simulate", problem, *settings(law, None, adjustment), "--out", out, "--force")
            made[law, adjustment] = out
    return made


@pytest.mark.slow
@pytest.mark.parametrize("adjustment", ADJUSTMENTS)
@pytest.mark.parametrize(("law", "endurance"), LAWS)
def test_simulate(law: str, endurance: str | None, adjustment: str, tmp_path: Path) -> None:
    problem = ADJUSTMENTS[adjustment][0]
    args = settings(law, endurance, adjustment)
    cli("simulate", problem, *args, "--out", tmp_path, "--force", "--no-figures", "--jobs", "1")
    for name in ("timeline.csv", "events.csv", "summary.json", "manifest.json", "report.html"):
        assert (tmp_path / name).is_file(), name
    made_by(tmp_path / "summary.json", law, endurance)


@pytest.mark.slow
@pytest.mark.parametrize("adjustment", ADJUSTMENTS)
@pytest.mark.parametrize("law", RECOVERY_LAWS)
def test_figures_rerun_and_evaluate(
    law: str, adjustment: str, runs: dict[tuple[str, str], Path], tmp_path: Path
) -> None:
    """The run's figures; rerun repeats it to the byte; evaluate reads its timeline as a
    recording and simulates the prediction beside it (which adjusts)."""
    run = runs[law, adjustment]
    assert {"postures.png", "fatigue.png", "active_torque.png"} <= {p.name for p in run.iterdir()}
    assert "identical" in cli("rerun", run / "manifest.json", "--out", tmp_path / "rerun")
    problem = ADJUSTMENTS[adjustment][0]
    out = tmp_path / "evaluate"
    cli(
        "evaluate",
        problem,
        *settings(law, None, adjustment),
        "--motion",
        run / "timeline.csv",
        "--compare-prediction",
        "--out",
        out,
    )
    made_by(out / "summary.json", law, None)
    made_by(out / "predicted" / "summary.json", law, None)


#: Each grid command's arguments and the file it writes (a case's summary.json below it).
GRIDS = {
    "whatif": (("--vary", "fatigue.r_min=0.8,0.9"), "whatif.csv"),
    "batch": ((), "summary.csv"),
    "duty-cycle": (("--t-off", "60", "--horizon", "600"), "duty_cycle.json"),
    "population": (("--n", "1", "--sex", "female", "--files"), "population.json"),
}


@pytest.mark.slow
@pytest.mark.parametrize("law", RECOVERY_LAWS)
@pytest.mark.parametrize("command", GRIDS)
def test_grids_and_people(command: str, law: str, tmp_path: Path) -> None:
    """whatif, batch, duty-cycle and population, each with every law; the adjustments take
    turns, so that each command runs both."""
    turn = (list(GRIDS).index(command) + list(RECOVERY_LAWS).index(law)) % len(ADJUSTMENTS)
    adjustment = list(ADJUSTMENTS)[turn]
    options, written = GRIDS[command]
    problem = ADJUSTMENTS[adjustment][0]
    output = cli(command, problem, *settings(law, None, adjustment), *options, "--out", tmp_path)
    assert (tmp_path / written).is_file()
    if command == "whatif":  # the law --set chose, not the file's
        assert f"recovery law: {law}" in output
    for summary in tmp_path.rglob("summary.json"):
        made_by(summary, law, None)
