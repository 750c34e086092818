"""BVH recordings: the file's Euler order, the rest pose and a known motion round-tripped."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest
from bvh_files import REST, SEATED, bvh_problem, bvh_problem_file, rotation, write_bvh
from click.testing import CliRunner
from recording_fuzzing import evaluate, invoke, problems

import casadi_posture as cp
from casadi_posture.cli import main
from casadi_posture.errors import ProblemError
from casadi_posture.ik.solvers import SOLVER_NAMES
from casadi_posture.motion.bvh import read_bvh


def _read(path: Path, problem: cp.Problem, solver: str = "nullspace"):
    spec = problem.spec.motion.bvh
    return read_bvh(path, problem.body, spec, problem.posture, solver, problem=problem.path)


def test_bvhio_composes_the_channels_in_the_file_s_order(tmp_path: Path) -> None:
    """One joint with 'Zrotation Xrotation Yrotation' at (40, 50, 60)°: Rz(40)·Rx(50)·Ry(60),
    computed by hand, not any other order."""
    from casadi_posture.motion.bvh import _read as read_file
    from casadi_posture.motion.bvh import _rotations

    text = (
        "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition "
        "Zrotation Xrotation Yrotation\n JOINT Arm\n {\n  OFFSET 0 1 0\n  CHANNELS 3 Zrotation "
        "Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 1 0\n  }\n }\n}\nMOTION\nFrames: 2\n"
        "Frame Time: 0.1\n0 0 0 0 0 0 40 50 60\n0 0 0 0 0 0 0 0 0\n"
    )
    path = tmp_path / "one.bvh"
    path.write_text(text)
    arm = read_file(path).Root.Children[0]
    expected = rotation("z", 40) @ rotation("x", 50) @ rotation("y", 60)
    np.testing.assert_allclose(_rotations(arm)[0], expected, atol=1e-6)
    assert (
        np.abs(_rotations(arm)[0] - rotation("x", 50) @ rotation("y", 60) @ rotation("z", 40)).max()
        > 0.1
    )


def test_the_rest_pose_is_the_rest_posture(tmp_path: Path) -> None:
    """The body at ``REST`` (shoulders abducted 90°) is the T-pose, every channel 0; read
    back, every channel 0 is that posture."""
    problem = bvh_problem()
    rest = np.zeros(problem.body.n)
    for dof, angle in REST.items():
        rest[problem.body.index[dof]] = math.radians(angle)
    path = write_bvh(tmp_path / "rest.bvh", problem, np.tile(rest, (3, 1)))
    frames = path.read_text().splitlines()[-3:]
    assert all(abs(float(v)) < 1e-9 for line in frames for v in line.split())
    np.testing.assert_allclose(_read(path, problem).q, np.tile(rest, (3, 1)), atol=1e-6)


@pytest.mark.parametrize("solver", SOLVER_NAMES)
def test_a_known_motion_round_trips(solver: str, tmp_path: Path) -> None:
    """A motion of every DOF written as BVH (float channels to 1e-9°) reads back to 1e-6 rad,
    its segments on their joints' orientations, and times from the frame time."""
    problem = bvh_problem()
    body = problem.body
    rng = np.random.default_rng(7)
    start = np.array([math.radians(0.5 * (d.lower + d.upper) / math.pi * 180) for d in body.dofs])
    steps = rng.uniform(-0.15, 0.15, size=(5, body.n))
    q = np.clip(
        start + np.cumsum(steps, axis=0),
        [d.lower + 0.2 for d in body.dofs],
        [d.upper - 0.2 for d in body.dofs],
    )
    path = write_bvh(tmp_path / "m.bvh", problem, q, frame_time=0.04)
    recording = _read(path, cp.load(SEATED, {**problem.overrides, "posture_deg": {}}), solver)
    np.testing.assert_allclose(recording.q, q, atol=1e-6)
    np.testing.assert_allclose(recording.time, np.arange(5) * 0.04)
    assert max(r.max() for r in recording.residuals.values()) < 1e-6
    assert recording.kind == "bvh" and not recording.flags


def test_bad_mappings_are_one_line_errors(tmp_path: Path) -> None:
    problem = bvh_problem()
    path = write_bvh(tmp_path / "m.bvh", problem, np.zeros((2, problem.body.n)))
    wrong = bvh_problem(joints={"RightArmm": "upper_arm_r", "Hips": "pelvis"})
    with pytest.raises(ProblemError, match="did you mean 'RightArm'"):
        _read(path, wrong)
    wrong = bvh_problem(joints={"RightArm": "upper_arm", "Hips": "pelvis"})
    with pytest.raises(ProblemError, match="a segment of the body"):
        _read(path, wrong)
    text = tmp_path / "not.bvh"
    text.write_text("time,elbow\n0,1\n")
    with pytest.raises(ProblemError, match="starts with HIERARCHY"):
        _read(text, problem)


def _defects(text: str) -> dict[str, tuple[str, str]]:
    """Defective copies of the BVH file ``text`` (3 frames), each with what evaluate's one
    line says of it."""
    lines = text.splitlines()
    motion = lines.index("MOTION")
    last = len(lines)
    value = lines[-1].split()

    def frame(k: int, changed: str) -> str:  # frame k's line with its first value changed
        row = lines[motion + 2 + k].split()
        return "\n".join(
            [*lines[: motion + 2 + k], " ".join([changed, *row[1:]]), *lines[motion + 3 + k :]]
        )

    return {
        "cut in the hierarchy": (
            "\n".join(lines[: motion // 2]),
            f"line {motion // 2 + 1} (the end of the file): expected a closing brace",
        ),
        "not BVH": (
            "HIERARCHY of needs\nesteem\n",
            "line 1 = 'HIERARCHY of needs': expected HIERARCHY",
        ),
        "a C3D file": ("\x02P" + "\x00" * 600, "a BVH file (it starts with HIERARCHY)"),
        "NaN": (
            frame(2, "nan"),
            f"frame 2 (line {motion + 5}), Hips Xposition = 'nan': expected a finite",
        ),
        "text": (
            frame(1, "abc"),
            f"frame 1 (line {motion + 4}), Hips Xposition = 'abc': expected a finite",
        ),
        "huge": (
            frame(3, "1e308"),
            f"frame 3 (line {last}), Hips Xposition = '1e308': expected a finite",
        ),
        "a value short": (
            "\n".join([*lines[:-1], " ".join(value[:-1])]),
            f"frame 3 (line {last}) = '{len(value) - 1} values': expected {len(value)} values",
        ),
        "more frames said": (text.replace("Frames: 3", "Frames: 5"), "expected frame 4 of the 5"),
        "frames past the limit": (
            text.replace("Frames: 3", "Frames: 999999999"),
            "2 to 100000 frames",
        ),
        "a frame more": (text + lines[-1] + "\n", f"line {last + 1} = "),
        "frame time": (
            text.replace("Frame Time: 0.5", "Frame Time: inf"),
            "= inf: expected a frame time",
        ),
        "a joint twice": (
            text.replace("JOINT LeftArm", "JOINT RightArm"),
            "JOINT RightArm': expected at most 500 joints, each named once",
        ),
    }


def test_defective_files_are_one_line_errors_and_never_hang(tmp_path: Path) -> None:
    """Each defect of ``_defects`` in evaluate: exit 2 within 30 s (bvhio waited forever on a
    file cut short), one line naming the file, the line and what was expected."""
    problem = bvh_problem()
    good = write_bvh(tmp_path / "m.bvh", problem, np.zeros((3, problem.body.n)), 0.5)
    file = bvh_problem_file(tmp_path / "seated.toml")
    for name, (text, said) in _defects(good.read_text()).items():
        path = tmp_path / f"{name.replace(' ', '_')}.bvh"
        path.write_text(text)
        invoked = invoke(evaluate(file, path, tmp_path / "out"))
        assert invoked.exit_code == 2, (name, invoked)
        assert not problems(invoked, path), name
        assert said in invoked.stderr, (name, invoked.stderr)


def test_evaluate_drives_the_body_with_a_bvh_file(tmp_path: Path) -> None:
    """The command line on a BVH file: the known angles in timeline.csv, each joint's fit
    residual per frame in degrees."""
    problem = bvh_problem()
    body = problem.body
    q = np.tile([0.5 * (d.lower + d.upper) for d in body.dofs], (3, 1))
    q[:, body.index["elbow_flexion_r"]] = np.radians([20.0, 40.0, 60.0])
    path = write_bvh(tmp_path / "m.bvh", problem, q, frame_time=0.5)
    file = bvh_problem_file(tmp_path / "seated.toml")
    out = tmp_path / "out"
    result = CliRunner().invoke(
        main, ["evaluate", str(file), "--motion", str(path), "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert "IK fit of the bvh file (7 targets)" in result.output
    rows = list(csv.DictReader((out / "timeline.csv").open()))
    assert [float(r["time_s"]) for r in rows] == [0.0, 0.5, 1.0]
    elbow = [float(r["elbow_flexion_r_deg"]) for r in rows]
    np.testing.assert_allclose(elbow, [20.0, 40.0, 60.0], atol=1e-4)
    assert max(float(r["bvh_residual_RightForeArm_deg"]) for r in rows) < 1e-4
    # the seated problem has a task: its residuals take the panel, not the fit
    assert "fit to the BVH joints (deg)" not in (out / "report.html").read_text()
