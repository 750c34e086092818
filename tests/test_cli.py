"""The command line: outputs, help examples, and every bad-input path (exit 2, one line)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

from casadi_posture.cli import main

GOOD = (PROBLEMS / "holding_m45.toml").read_text()


def run(*args: str):
    return CliRunner().invoke(main, list(args))


def _bad(tmp_path: Path, text: str, *extra: str):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    return path, run(*(extra or ("validate",)), str(path))


def test_every_shipped_problem_validates() -> None:
    result = run("validate", *map(str, sorted(PROBLEMS.glob("*.toml"))))
    assert result.exit_code == 0, result.output
    assert result.stdout.count("ok ") == len(list(PROBLEMS.glob("*.toml")))


@pytest.mark.parametrize(
    "command", ["validate", "describe", "torques", "curve", "solve", "compare"]
)
def test_help_shows_an_example(command: str) -> None:
    result = run(command, "--help")
    assert result.exit_code == 0
    assert f"casadi-posture {command} problems/" in result.stdout


def test_torques_json_and_table_agree() -> None:
    path = str(PROBLEMS / "holding_m45.toml")
    data = json.loads(run("torques", path, "--json").stdout)
    assert [d["name"] for d in data["dofs"]] == ["shoulder_flexion", "elbow_flexion"]
    flexors = data["half_joints"][0]
    assert flexors["name"] == "shoulder_flexors"
    assert flexors["load_pct_mvc"] == pytest.approx(
        100 * flexors["torque_Nm"] / flexors["strength_Nm"]
    )
    assert data["half_joints"][1]["endurance_min"] is None
    text = run("torques", path).stdout
    assert "load (%MVC)" in text and "endurance (min)" in text and "active (N·m)" in text
    assert f"{flexors['load_pct_mvc']:.2f}" in text


def test_torques_posture_option_changes_the_posture() -> None:
    path = str(PROBLEMS / "holding_m45.toml")
    data = json.loads(
        run(
            "torques",
            path,
            "--json",
            "--posture",
            "shoulder_flexion=90",
            "--posture",
            "elbow_flexion=0",
        ).stdout
    )
    assert data["dofs"][0]["angle_deg"] == pytest.approx(90.0)
    assert data["dofs"][0]["external_Nm"] == pytest.approx(-24.06, abs=0.01)


def test_describe_lists_model_and_parameter_sources() -> None:
    data = json.loads(run("describe", str(PROBLEMS / "holding_m45.toml"), "--json").stdout)
    assert data["dofs"][1]["parent"] == "shoulder_flexion"
    assert data["dofs"][1]["origin_m"] == pytest.approx([0, 0, -0.2817])
    assert data["loads"][0]["point_m"] == pytest.approx([0, 0, -0.2817 - 0.2689])
    assert data["loads"][0]["dof"] == "elbow_flexion"
    names = {p["name"]: p for p in data["parameters"]}
    assert names["strength.elbow_flexors"]["status"] == "estimate"
    assert names["segment.upper_arm.mass"]["status"] == "verified"
    assert all(p["source"] and p["unit"] is not None for p in data["parameters"])
    text = run("describe", str(PROBLEMS / "holding_m45.toml")).stdout
    assert "de Leva" in text and "moved by DOF" in text


def test_overrides_are_marked_as_user_values(tmp_path: Path) -> None:
    text = GOOD.replace(
        "[posture_deg]",
        "[body.segments.forearm]\nmass_kg = 1.5\n\n"
        "[body.half_joints.elbow_flexors]\nstrength_Nm = 55.0\n\n[posture_deg]",
    )
    path = tmp_path / "override.toml"
    path.write_text(text)
    data = json.loads(run("describe", str(path), "--json").stdout)
    names = {p["name"]: p for p in data["parameters"]}
    assert names["segment.forearm.mass"]["value"] == 1.5
    assert names["segment.forearm.mass"]["status"] == "user"
    assert names["strength.elbow_flexors"] == {
        **names["strength.elbow_flexors"],
        "value": 55.0,
        "status": "user",
    }


def test_curve_prints_zeros_and_writes_the_figure(tmp_path: Path) -> None:
    out = tmp_path / "fig3.png"
    result = run(
        "curve", str(PROBLEMS / "frontal_elbow.toml"), "--dof", "elbow_flexion", "--out", str(out)
    )
    assert result.exit_code == 0, result.output
    assert out.stat().st_size > 10_000
    assert result.stdout.count("passive: τp carries τe") == 2
    assert result.stdout.count("active: τe ≈ 0") == 1


BAD_FILES = [
    ("unknown top-level key", GOOD + "\ncolour = 'red'\n", "colour"),
    (
        "unknown nested key",
        GOOD.replace("mass_kg = 73.0", "mass_kg = 73.0\nweight = 3"),
        "body.weight",
    ),
    ("unknown task key", GOOD.replace("priority = 2", "priority = 2\nspeed = 1"), "tasks[1].speed"),
    ("wrong type", GOOD.replace("stature_m = 1.741", 'stature_m = "tall"'), "body.stature_m"),
    ("negative load mass", GOOD.replace("mass_kg = 2.5", "mass_kg = -2.5"), "loads[0].mass_kg"),
    ("negative body mass", GOOD.replace("mass_kg = 73.0", "mass_kg = -73.0"), "body.mass_kg"),
    (
        "negative segment mass",
        GOOD.replace("[posture_deg]", "[body.segments.hand]\nmass_kg = -1\n[posture_deg]"),
        "body.segments.hand.mass_kg",
    ),
    (
        "range min >= max",
        GOOD.replace(
            "[posture_deg]", "[body.dofs.elbow_flexion]\nrange_deg = [150.0, 0.0]\n[posture_deg]"
        ),
        "body.dofs.elbow_flexion.range_deg",
    ),
    (
        "thresholds reversed",
        GOOD.replace("recovery_threshold = 0.5", "recovery_threshold = 0.9"),
        "fatigue",
    ),
    (
        "threshold above 1",
        GOOD.replace("fatigue_threshold = 0.8", "fatigue_threshold = 1.2"),
        "fatigue.fatigue_threshold",
    ),
    (
        "unknown DOF in posture",
        GOOD.replace("elbow_flexion = 77.2878", "wrist_flexion = 10.0"),
        "posture_deg.wrist_flexion",
    ),
    (
        "unknown DOF override",
        GOOD.replace("[posture_deg]", "[body.dofs.knee]\nrange_deg = [0.0, 1.0]\n[posture_deg]"),
        "body.dofs.knee",
    ),
    (
        "posture out of range",
        GOOD.replace("elbow_flexion = 77.2878", "elbow_flexion = 170.0"),
        "posture_deg.elbow_flexion",
    ),
    ("unknown model", GOOD.replace('model = "sagittal_arm"', 'model = "octopus"'), "body.model"),
    (
        "unknown endurance model",
        GOOD.replace('endurance = "manenica"', 'endurance = "guess"'),
        "fatigue.endurance",
    ),
    (
        "unknown fatigue model",
        GOOD.replace('recovery_law = "threshold"', 'recovery_law = "magic"'),
        "fatigue.recovery_law",
    ),
    (
        "unknown strategy",
        GOOD.replace('strategy = "active"', 'strategy = "lazy"'),
        "fatigue.strategy",
    ),
    ("unknown task kind", GOOD.replace('kind = "position"', 'kind = "teleport"'), "tasks[1]"),
    (
        "unknown effector",
        GOOD.replace('effector = "wrist"\npriority = 2', 'effector = "thumb"\npriority = 2'),
        "tasks[1].effector",
    ),
    ("unknown load point", GOOD.replace('at = "wrist"', 'at = "pocket"'), "loads[0].at"),
    (
        "vector of 2",
        GOOD.replace("target_m = [0.35, 0.0, -0.25]", "target_m = [0.35, 0.0]"),
        "tasks[1].target_m",
    ),
    ("missing body", GOOD.replace("[body]", "[bodyy]"), "body"),
    (
        "unknown half-joint",
        GOOD.replace(
            "[posture_deg]", "[body.half_joints.toe_flexors]\nstrength_Nm = 5.0\n[posture_deg]"
        ),
        "body.half_joints.toe_flexors",
    ),
    ("zero priority", GOOD.replace("priority = 1", "priority = 0"), "tasks[0].priority"),
]


@pytest.mark.parametrize(("case", "text", "key"), BAD_FILES, ids=[c[0] for c in BAD_FILES])
def test_bad_files_give_one_line_naming_the_key(
    tmp_path: Path, case: str, text: str, key: str
) -> None:
    path, result = _bad(tmp_path, text)
    assert result.exit_code == 2, (case, result.output)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert str(path) in lines[0] and key in lines[0] and "expected" in lines[0]
    assert "Traceback" not in result.output


def test_missing_and_malformed_files(tmp_path: Path) -> None:
    missing = run("torques", str(tmp_path / "nope.toml"))
    assert missing.exit_code == 2 and "nope.toml" in missing.stderr and "exist" in missing.stderr
    _, result = _bad(tmp_path, "[body\nmodel = 1")
    assert result.exit_code == 2 and "valid TOML" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--posture", "knee=10"], "--posture = 'knee'"),
        (["--posture", "elbow_flexion"], "--posture"),
        (["--posture", "elbow_flexion=abc"], "--posture"),
        (["--posture", "elbow_flexion=200"], "--posture.elbow_flexion"),
    ],
)
def test_bad_posture_option(args: list[str], needle: str) -> None:
    result = run("torques", str(PROBLEMS / "holding_m45.toml"), *args)
    assert result.exit_code == 2
    assert len(result.stderr.strip().splitlines()) == 1 and needle in result.stderr


def test_bad_dof_for_curve() -> None:
    result = run("curve", str(PROBLEMS / "holding_m45.toml"), "--dof", "knee")
    assert result.exit_code == 2 and "--dof = 'knee'" in result.stderr


def test_console_script_exit_code_and_no_traceback(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(GOOD.replace("mass_kg = 2.5", "mass_kg = -1.0"))
    done = subprocess.run(
        [sys.executable, "-m", "casadi_posture", "validate", str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "loads[0].mass_kg = -1.0" in done.stderr
    assert "Traceback" not in done.stderr


def test_a_passive_override_without_model_is_the_exponential(tmp_path: Path) -> None:
    """The form docs/problem-files.md documents: no 'model' key."""
    path = tmp_path / "override.toml"
    path.write_text(
        GOOD.replace(
            "[posture_deg]",
            "[body.dofs.elbow_flexion]\npassive = { k1_Nm "
            "= 2.0, k2_per_rad = 20.0, q1_deg = 0.0, k3_Nm = 1.0, k4_per_rad"
            " = 8.0, q2_deg = 120.0 }\n\n[posture_deg]",
        )
    )
    data = json.loads(run("describe", str(path), "--json").stdout)
    names = {p["name"]: p for p in data["parameters"]}
    assert names["joints.elbow_flexion.passive.k1"]["value"] == 2.0
    bad = tmp_path / "bad.toml"
    bad.write_text(
        GOOD.replace(
            "[posture_deg]",
            '[body.dofs.elbow_flexion]\npassive = { model = "springy" }\n\n[posture_deg]',
        )
    )
    result = run("validate", str(bad))
    assert result.exit_code == 2
    assert (
        "passive = 'springy': expected one of 'exponential', 'limit_torque', 'gymnast_fit', 'none'"
        in result.stderr
    )


@pytest.mark.parametrize("command", ["torques", "solve"])
def test_a_3d_table_shows_the_most_loaded_groups_and_all_with_the_flag(command: str) -> None:
    """On the 29-DOF body the table lists the ten half-joints of the largest load (as the
    JSON ranks them) and their DOFs, then says how many more there are; --all lists all 58.
    The 2-DOF arm's four groups are always all shown."""
    path = str(PROBLEMS / "standing_wall_horizontal.toml")
    data = json.loads(run(command, path, "--json").stdout)
    groups = data["half_joints"] if command == "torques" else data["torques"]["half_joints"]
    top = sorted(groups, key=lambda g: -g["load_pct_mvc"])[:10]
    text = run(command, path).stdout
    shown = [
        line.split()[0]
        for line in text.splitlines()
        if line.split()[:1] and any(line.startswith(g["name"] + " ") for g in groups)
    ]
    assert sorted(shown) == sorted(g["name"] for g in top)
    assert f"... {len(groups) - 10} more half-joints" in text
    hidden = max(g["load_pct_mvc"] for g in groups if g not in top)
    assert f"carry at most {hidden:.1f} %MVC" in text
    every = run(command, path, "--all").stdout
    assert sum(
        any(line.startswith(g["name"] + " ") for g in groups) for line in every.splitlines()
    ) == len(groups)
    assert "more half-joints" not in every
    arm = run(command, str(PROBLEMS / "holding_m45.toml")).stdout
    assert "more half-joints" not in arm and "elbow_extensors" in arm


def test_simulate_names_the_joints_that_moved_and_the_groups_that_matter(tmp_path: Path) -> None:
    """A 3-D run's table shows the ten groups of largest load or fatigue, its recovery line
    the joints that moved most (their start and recovery angles, as summary.json records),
    and the times in seconds and minutes; --all shows every group and joint."""
    path = str(PROBLEMS / "standing_wall_horizontal.toml")
    out = tmp_path / "run"
    text = run("simulate", path, "--duration", "600", "--no-report", "--out", str(out)).stdout
    summary = json.loads((out / "summary.json").read_text())
    assert "... 48 more half-joints" in text
    first = "first at the fatigue threshold: shoulder_flexors_r (shoulder) at 249 s (4.2 min)"
    assert first in text
    recovery = summary["recovery_postures"][0]
    line = next(x for x in text.splitlines() if x.strip().startswith("recovered at"))
    assert line.strip().startswith(f"recovered at {recovery['time_s']:g} s (")
    named = [part.split()[0] for part in line.split(": ", 1)[1].split(", ")[:-1]]
    angles = recovery["posture_deg"]
    timeline = np.loadtxt(out / "timeline.csv", delimiter=",", skiprows=1, max_rows=1, dtype=str)
    header = (out / "timeline.csv").read_text().splitlines()[0].split(",")
    start = {k: float(timeline[header.index(f"{k}_deg")]) for k in angles}
    moved = sorted(angles, key=lambda k: -abs(angles[k] - start[k]))
    assert named == moved[: len(named)] and 1 <= len(named) <= 4
    assert f"{named[0]} {start[named[0]]:.1f} → {angles[named[0]]:.1f}°" in line
    assert line.endswith(
        f"{len(angles) - len(named)} other joints within "
        f"{abs(angles[moved[len(named)]] - start[moved[len(named)]]):.1f}°"
    )
    every = run(
        "simulate", path, "--duration", "600", "--no-report", "--all", "--out", str(tmp_path / "b")
    ).stdout
    assert "more half-joints" not in every and "other joints within" not in every
