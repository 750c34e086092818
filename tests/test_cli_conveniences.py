"""What users of opensim-cmd and Hydra expect of a command line: init, --set on every
command, one rule for every output, rerun from a manifest, paired what-if cases."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

import casadi_posture as cp
from casadi_posture.cli import main
from casadi_posture.runs.whatif_plots import OUTCOMES

HOLD = PROBLEMS / "holding_m45.toml"


def test_init_writes_a_file_that_validates_and_refuses_to_overwrite(tmp_path: Path) -> None:
    runner = CliRunner()
    for name in ("hold", "elbow", "tree", "shelf", "seated"):
        path = tmp_path / f"{name}.toml"
        assert runner.invoke(main, ["init", name, str(path)]).exit_code == 0
        assert runner.invoke(main, ["validate", str(path)]).exit_code == 0
        again = runner.invoke(main, ["init", name, str(path)])
        assert again.exit_code == 2 and "--force" in again.stderr
        assert runner.invoke(main, ["init", name, str(path), "--force"]).exit_code == 0
    assert runner.invoke(main, ["init", str(tmp_path / "default.toml")]).exit_code == 0


@pytest.mark.parametrize("name", ["shelf", "seated"])
def test_the_3d_templates_hold_their_task_plausibly(name: str, tmp_path: Path) -> None:
    """A newcomer's first 3-D file: solved without a flag (the task achieved, balanced, no
    posture a source calls extreme), a two-hand task held mirror-symmetrically."""
    path = tmp_path / f"{name}.toml"
    assert CliRunner().invoke(main, ["init", name, str(path)]).exit_code == 0
    answer = cp.solve(cp.load(path))
    assert answer.reached and not answer.flags, answer.flags
    if name == "shelf":
        assert answer.plausibility.asymmetry_deg < 1e-3


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


def _two_problems(folder: Path) -> Path:
    folder.mkdir()
    for name in ("holding_m45", "holding_m25"):
        text = (PROBLEMS / f"{name}.toml").read_text()
        (folder / f"{name}.toml").write_text(
            text.replace("duration_s = 1800.0", "duration_s = 5.0")
        )
    return folder


def test_force_never_deletes_the_current_folder_or_the_inputs(tmp_path: Path, monkeypatch) -> None:
    """Reproducers: `batch ../two --out . --force` wiped the current folder, and
    `batch inputs --out inputs --force` deleted the problem files."""
    inputs = _two_problems(tmp_path / "inputs")
    here = tmp_path / "here"
    here.mkdir()
    (here / "precious.txt").write_text("mine")
    monkeypatch.chdir(here)
    runner = CliRunner()
    for out in (".", "", ".."):
        result = runner.invoke(main, ["batch", str(inputs), "--out", out, "--force", "--quiet"])
        assert result.exit_code == 2 and "not the current folder" in result.stderr, out
    into_inputs = runner.invoke(
        main, ["batch", str(inputs), "--out", str(inputs), "--force", "--quiet"]
    )
    assert into_inputs.exit_code == 2 and "apart from the problem files" in into_inputs.stderr
    assert (here / "precious.txt").read_text() == "mine"
    assert sorted(p.name for p in inputs.iterdir()) == ["holding_m25.toml", "holding_m45.toml"]


def test_force_starts_a_run_over_and_keeps_the_users_files(tmp_path: Path) -> None:
    inputs = _two_problems(tmp_path / "inputs")
    out = tmp_path / "out"
    runner = CliRunner()
    args = ["whatif", str(inputs / "holding_m45.toml"), "--vary", "loads[0].mass_kg=1,2"]
    assert runner.invoke(main, [*args, "--out", str(out), "--quiet"]).exit_code == 0
    (out / "notes.txt").write_text("mine")
    again = runner.invoke(main, [*args[:-1], "loads[0].mass_kg=3", "--out", str(out), "--force"])
    assert again.exit_code == 0, again.output
    assert (out / "notes.txt").read_text() == "mine"
    assert sorted(p.name for p in (out / "cases").iterdir()) == ["mass_kg=3"]
    # one figure per outcome of a simulated what-if (runs/whatif_plots.py OUTCOMES) that a
    # case has a value for: not the first group at the threshold (never reached in 5 s) nor
    # the low-back compression (a planar arm has no lumbar joint)
    assert len(list(out.glob("whatif_*.png"))) == len(OUTCOMES) - 2


def test_a_rerun_inside_a_batch_does_not_break_its_resume(tmp_path: Path) -> None:
    """Reproducer: rerun wrote cases/<case>-rerun/, which --resume then read as a case."""
    inputs = _two_problems(tmp_path / "inputs")
    out = tmp_path / "b"
    runner = CliRunner()
    assert runner.invoke(main, ["batch", str(inputs), "--out", str(out), "--quiet"]).exit_code == 0
    manifest = out / "cases" / "holding_m45" / "manifest.json"
    rerun = runner.invoke(main, ["rerun", str(manifest)])
    assert rerun.exit_code == 0 and "identical" in rerun.output
    resumed = runner.invoke(main, ["batch", str(inputs), "--out", str(out), "--resume"])
    assert resumed.exit_code == 0, resumed.output
    assert "2 cases (0 run now, 2 already done)" in resumed.output


def test_rerun_flags_a_manifest_without_its_summary(tmp_path: Path) -> None:
    runner = CliRunner()
    out = tmp_path / "run"
    args = ["simulate", str(HOLD), "--duration", "5", "--out", str(out)]
    assert runner.invoke(main, args).exit_code == 0
    (out / "summary.json").unlink()
    result = runner.invoke(main, ["rerun", str(out / "manifest.json")])
    assert result.exit_code == 1 and "FLAGGED: no summary.json" in result.output


def test_rerun_refuses_the_manifest_s_own_folder(tmp_path: Path) -> None:
    """Written there, the rerun would be compared with itself and always be identical."""
    runner = CliRunner()
    out = tmp_path / "run"
    args = ["simulate", str(HOLD), "--duration", "5", "--out", str(out)]
    assert runner.invoke(main, args).exit_code == 0
    before = (out / "summary.json").read_bytes()
    args = ["rerun", str(out / "manifest.json"), "--out", str(out), "--force"]
    result = runner.invoke(main, args)
    assert result.exit_code == 2 and "a folder apart from the manifest's" in result.stderr
    assert (out / "summary.json").read_bytes() == before


def test_validate_reports_every_file_and_reads_folders(tmp_path: Path) -> None:
    (tmp_path / "bad.toml").write_text("x = 1\n")
    (tmp_path / "good.toml").write_text(HOLD.read_text())
    result = CliRunner().invoke(main, ["validate", str(tmp_path / "bad.toml"), str(PROBLEMS)])
    assert result.exit_code == 2
    assert result.stderr.count("error:") == 1 and "bad.toml" in result.stderr
    assert result.output.count("ok  ") == len(list(PROBLEMS.glob("*.toml")))


def test_init_with_a_template_name_alone_asks_for_the_file(tmp_path: Path, monkeypatch) -> None:
    """Reproducer: `init elbow` wrote a file named `elbow` from the hold template."""
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(main, ["init", "elbow"])
    assert result.exit_code == 2 and "the file to write after elbow" in result.stderr
    nowhere = CliRunner().invoke(main, ["init", str(tmp_path / "no" / "such" / "x.toml")])
    assert nowhere.exit_code == 2 and not (tmp_path / "no").exists()
    assert list(tmp_path.iterdir()) == []


def test_vary_twice_one_key_is_refused_and_paired_values_may_repeat(tmp_path: Path) -> None:
    runner = CliRunner()
    twice = runner.invoke(
        main,
        [
            "whatif",
            str(HOLD),
            "--static",
            "--out",
            str(tmp_path / "t"),
            "--vary",
            "loads[0].mass_kg=1,2",
            "--vary",
            "loads[0].mass_kg=3",
        ],
    )
    assert twice.exit_code == 2 and "each key varied once" in twice.stderr
    paired = runner.invoke(
        main,
        [
            "whatif",
            str(HOLD),
            "--static",
            "--paired",
            "--quiet",
            "--out",
            str(tmp_path / "p"),
            "--vary",
            "loads[0].mass_kg=1,2.5,5",
            "--vary",
            "body.sex=male,female,male",
        ],
    )
    assert paired.exit_code == 0, paired.stderr
    assert len(list((tmp_path / "p" / "cases").iterdir())) == 3
    mismatch = runner.invoke(
        main,
        [
            "whatif",
            str(HOLD),
            "--static",
            "--paired",
            "--out",
            str(tmp_path / "m"),
            "--vary",
            "loads[0].mass_kg=1,2",
            "--vary",
            "body.sex=male",
        ],
    )
    assert mismatch.exit_code == 2
    assert "{'loads[0].mass_kg': 2, 'body.sex': 1}" in mismatch.stderr


def test_posture_and_set_errors_name_the_key_and_value() -> None:
    runner = CliRunner()
    posture = runner.invoke(main, ["torques", str(HOLD), "--posture", "elbow=10"])
    assert posture.exit_code == 2
    assert "--posture = 'elbow': expected a DOF of sagittal_arm" in posture.stderr
    table = runner.invoke(main, ["torques", str(HOLD), "--set", "loads[0]=5"])
    assert table.exit_code == 2 and "loads[0] = 5: expected a table of keys" in table.stderr
