"""One grammar for every command-line option that takes a time (cli/durations.py)."""

from __future__ import annotations

import json
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from casadi_posture.cli import main
from casadi_posture.cli.durations import GRAMMAR, Seconds, seconds

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"

#: Every option that takes a time, by command.
TIMED = {
    "simulate": {"--duration"},
    "evaluate": {"--between", "--resample", "--until"},
    "duty-cycle": {"--t-off", "--horizon", "--tolerance"},
}


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("600", 600.0),
        ("600s", 600.0),
        ("10min", 600.0),
        ("1.5min", 90.0),
        (".5h", 1800.0),
        ("8h", 28800.0),
        ("2e1s", 20.0),
        (" 20 s ", 20.0),
        ("-3", -3.0),  # the grammar reads it; each command checks its own range
    ],
)
def test_a_time_is_seconds_or_a_number_with_a_unit(text: str, expected: float) -> None:
    assert seconds(text) == expected


@pytest.mark.parametrize("text", ["8 hours", "10m", "inf", "nan", "", "1e999", "2h30min", "s"])
def test_anything_else_is_refused_with_the_grammar(text: str) -> None:
    with pytest.raises(ValueError, match="a time in s, or with a unit s, min or h"):
        seconds(text)


def test_every_option_that_takes_seconds_reads_the_grammar() -> None:
    """The options listed above have the one type; no other option takes a plain float
    whose help speaks of seconds (a new one would be refused a unit again)."""
    for name, command in main.commands.items():
        for param in command.params:
            if not isinstance(param, click.Option):
                continue
            types = getattr(param.type, "types", [param.type])
            timed = all(isinstance(t, Seconds) for t in types)
            assert timed == (param.opts[0] in TIMED.get(name, set())), (name, param.opts)
            if param.type == click.FLOAT:
                assert " s " not in f" {param.help} ", (name, param.opts)


@pytest.mark.parametrize(
    ("command", "option", "value"),
    [
        ("simulate", "--duration", "10 minutes"),
        ("duty-cycle", "--t-off", "20s,1m"),
        ("duty-cycle", "--horizon", "8hours"),
        ("duty-cycle", "--tolerance", "5sec"),
        ("evaluate", "--until", "1 hour"),
        ("evaluate", "--resample", "0.1 s."),
    ],
)
def test_a_bad_time_is_one_line_naming_the_option_the_value_and_the_grammar(
    command: str, option: str, value: str
) -> None:
    problem = str(PROBLEMS / "holding_horizontal.toml")
    required = {"duty-cycle": ["--t-off", "30"], "evaluate": ["--motion", "x.csv"]}
    args = [command, problem, *required.get(command, []), option, value]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    assert option in lines[0] and repr(value) in lines[0] and GRAMMAR in lines[0]


def test_a_duration_with_a_unit_is_simulated(tmp_path: Path) -> None:
    """``--duration 1.5min`` simulates 90 s, as ``--duration 90`` did."""
    out = tmp_path / "run"
    args = ["simulate", str(PROBLEMS / "holding_m45.toml"), "--duration", "1.5min"]
    result = CliRunner().invoke(main, [*args, "--no-figures", "--no-report", "--out", str(out)])
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["duration_s"] == summary["simulated_s"] == 90.0
