"""What users of opensim-cmd and Hydra expect of a command line: init, --set on every
command, one rule for every output, rerun from a manifest, paired what-if cases."""

from __future__ import annotations

import json
import re
from pathlib import Path

from click.testing import CliRunner
from conftest import PROBLEMS

from casadi_posture.cli import main

HOLD = PROBLEMS / "holding_m45.toml"


def test_init_writes_a_file_that_validates_and_refuses_to_overwrite(tmp_path: Path) -> None:
    runner = CliRunner()
    for name in ("hold", "elbow"):
        path = tmp_path / f"{name}.toml"
        assert runner.invoke(main, ["init", name, str(path)]).exit_code == 0
        assert runner.invoke(main, ["validate", str(path)]).exit_code == 0
        again = runner.invoke(main, ["init", name, str(path)])
        assert again.exit_code == 2 and "--force" in again.stderr
        assert runner.invoke(main, ["init", name, str(path), "--force"]).exit_code == 0
    assert runner.invoke(main, ["init", str(tmp_path / "default.toml")]).exit_code == 0


def test_rerun_reproduces_the_summary_byte_for_byte(tmp_path: Path) -> None:
    runner = CliRunner()
    out = tmp_path / "run"
    first = runner.invoke(
        main,
        [
            "simulate",
            str(HOLD),
            "--duration",
            "240",
            "--set",
            "loads[0].mass_kg=3",
            "--solver",
            "nullspace",
            "--out",
            str(out),
        ],
    )
    assert first.exit_code == 0, first.output
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["overrides"]["loads[0].mass_kg"] == 3
    again = runner.invoke(main, ["rerun", str(out / "manifest.json")])
    assert again.exit_code == 0, again.output
    assert "summary.json identical to" in again.output
    rerun = tmp_path / "run-rerun"
    assert (rerun / "summary.json").read_bytes() == (out / "summary.json").read_bytes()


def test_set_is_validated_like_the_file(tmp_path: Path) -> None:
    runner = CliRunner()
    bad = runner.invoke(main, ["solve", str(HOLD), "--set", "loads[0].mass_kg=-1"])
    assert bad.exit_code == 2
    assert bad.stderr.strip() == (
        f"error: {HOLD}: loads[0].mass_kg = -1: expected greater than or equal to 0 kg"
    )
    typo = runner.invoke(main, ["torques", str(HOLD), "--set", "loads[0].mass_kgg=1"])
    assert typo.exit_code == 2 and "mass_kgg" in typo.stderr
    shape = runner.invoke(main, ["describe", str(HOLD), "--set", "nokey"])
    assert shape.exit_code == 2 and "KEY=VALUE" in shape.stderr
    good = runner.invoke(main, ["torques", str(HOLD), "--set", "loads[0].mass_kg=5", "--json"])
    assert json.loads(good.stdout)["half_joints"][0]["load_pct_mvc"] > 40


def test_every_output_follows_one_rule(tmp_path: Path) -> None:
    runner = CliRunner()
    taken = tmp_path / "taken"
    taken.mkdir()
    (taken / "x").write_text("x")
    for args in (
        ["simulate", str(HOLD), "--duration", "5", "--out", str(taken)],
        ["compare", str(HOLD), "--out", str(taken)],
        ["whatif", str(HOLD), "--vary", "loads[0].mass_kg=1", "--static", "--out", str(taken)],
    ):
        result = runner.invoke(main, args)
        assert result.exit_code == 2 and "--force" in result.stderr, args
    empty = runner.invoke(main, ["simulate", str(HOLD), "--duration", "5", "--out", ""])
    assert empty.exit_code == 2
    forced = runner.invoke(
        main, ["simulate", str(HOLD), "--duration", "5", "--out", str(taken), "--force"]
    )
    assert forced.exit_code == 0 and (taken / "summary.json").exists()


def test_paired_whatif_pairs_instead_of_a_grid(tmp_path: Path) -> None:
    result = CliRunner().invoke(
        main,
        [
            "whatif",
            str(HOLD),
            "--static",
            "--paired",
            "--quiet",
            "--out",
            str(tmp_path / "w"),
            "--vary",
            "body.sex=female,male",
            "--vary",
            "body.stature_m=1.52,1.87",
        ],
    )
    assert result.exit_code == 0, result.output
    rows = [
        line.split()[:2]
        for line in result.output.splitlines()
        if re.match(r"^(female|male) ", line)
    ]
    assert rows == [["female", "1.52"], ["male", "1.87"]]
    uneven = CliRunner().invoke(
        main,
        [
            "whatif",
            str(HOLD),
            "--static",
            "--paired",
            "--out",
            str(tmp_path / "u"),
            "--vary",
            "body.sex=female,male",
            "--vary",
            "body.stature_m=1.52",
        ],
    )
    assert uneven.exit_code == 2 and "lists of one length" in uneven.stderr
