"""rerun reads a manifest.json through a schema (runs/manifest.py): a hand-edited field is
one line naming the file, the key, the value and what was expected, before anything runs."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

from casadi_posture.cli import main
from casadi_posture.runs.manifest import read_manifest

QUICK = ["--duration", "5", "--no-figures", "--no-report"]


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A simulation's folder and an evaluation's (of the simulation's timeline)."""
    folder = tmp_path_factory.mktemp("runs")
    hold = str(PROBLEMS / "holding_m45.toml")
    simulated, evaluated = folder / "simulated", folder / "evaluated"
    done = CliRunner().invoke(main, ["simulate", hold, *QUICK, "--out", str(simulated)])
    assert done.exit_code == 0, done.output
    motion = ["--motion", str(simulated / "timeline.csv"), "--between", "0", "4"]
    done = CliRunner().invoke(main, ["evaluate", hold, *motion, "--out", str(evaluated)])
    assert done.exit_code == 0, done.output
    return {"simulation": simulated, "evaluation": evaluated}


def test_both_kinds_of_manifest_read_as_written(runs: dict[str, Path]) -> None:
    simulated = read_manifest(runs["simulation"] / "manifest.json")
    assert simulated.recording is None and simulated.solver == "lexicographic"
    evaluated = read_manifest(runs["evaluation"] / "manifest.json")
    assert evaluated.recording is not None
    assert evaluated.recording.options() == {
        "solver": None,
        "between_s": (0.0, 4.0),
        "resample_s": None,
        "repeat_times": None,
        "until_s": None,
    }


@pytest.mark.parametrize(
    ("run", "key", "value", "line"),
    [
        ("simulation", "problem_data", None, "problem_data = null: expected the problem's tables"),
        ("simulation", "problem_data", [1, 2], "problem_data = [1, 2]: expected the problem's"),
        ("simulation", "problem_path", 7, "problem_path = 7: expected the problem file's path"),
        ("simulation", "solver", "x", "solver = \"x\": expected one of ['nullspace', "),
        ("simulation", "recording", "x", 'recording = "x": expected null (a simulation) or'),
        ("evaluation", "recording", None, 'solver = "recorded": expected one of'),
        ("evaluation", "recording.between_s", "0 4", 'recording.between_s = "0 4": expected'),
        ("evaluation", "recording.between_s", 7, "recording.between_s = 7: expected null or a"),
        ("evaluation", "recording.between_s", [4, 0], "[4, 0]: expected null or a pair [START,"),
        ("evaluation", "recording.between_s", ["0", "4"], 'between_s = ["0", "4"]: expected'),
        ("evaluation", "recording.resample_s", True, "recording.resample_s = true: expected"),
        ("evaluation", "recording.repeat_times", 0, "recording.repeat_times = 0: expected"),
        ("evaluation", "recording.sha256", None, "recording.sha256 = null: expected the"),
        ("evaluation", "recording.source", [1], "recording.source = [1]: expected the recording"),
    ],
)
def test_a_hand_edited_field_is_one_line_naming_it(
    runs: dict[str, Path], tmp_path: Path, run: str, key: str, value: object, line: str
) -> None:
    record = json.loads((runs[run] / "manifest.json").read_text())
    table, _, field = key.rpartition(".")
    (record[table] if table else record)[field] = value
    manifest = tmp_path / "manifest.json"
    manifest.write_text(json.dumps(record))
    out = tmp_path / "rerun"
    result = CliRunner().invoke(main, ["rerun", str(manifest), "--out", str(out)])
    assert result.exit_code == 2, result.output
    assert result.stderr.startswith(f"error: {manifest}: ") and line in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
    assert not out.exists()  # refused before anything ran
