"""BVH recordings: the file's Euler order, the rest pose and a known motion round-tripped."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from click.testing import CliRunner

import casadi_posture as cp
from casadi_posture.cli import main
from casadi_posture.errors import ProblemError
from casadi_posture.ik.solvers import SOLVER_NAMES
from casadi_posture.motion.bvh import read_bvh

SEATED = "problems/seated_assembly.toml"
#: The file's axes: y up, the skeleton facing +z (most BVH files).
AXES = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
#: A T-pose: the body's shoulders abducted 90° when every channel is 0.
REST = {"shoulder_abduction_r": 90.0, "shoulder_abduction_l": 90.0}
#: BVH joint: (its parent, the segment it moves).
SKELETON = {
    "Hips": (None, "pelvis"),
    "Chest": ("Hips", "upper_trunk"),
    "RightArm": ("Chest", "upper_arm_r"),
    "RightForeArm": ("RightArm", "forearm_r"),
    "RightHand": ("RightForeArm", "hand_r"),
    "LeftArm": ("Chest", "upper_arm_l"),
    "LeftForeArm": ("LeftArm", "forearm_l"),
    "LeftHand": ("LeftForeArm", "hand_l"),
}


def _r(axis: str, degrees: float) -> np.ndarray:
    a = math.radians(degrees)
    c, s = math.cos(a), math.sin(a)
    return {
        "x": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]),
        "y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
        "z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]),
    }[axis]


def _zxy(r: np.ndarray) -> tuple[float, float, float]:
    """Euler angles [deg] of R = Rz(a)·Rx(b)·Ry(c), the order of 'Zrotation Xrotation
    Yrotation' channels."""
    b = math.asin(max(-1.0, min(1.0, r[2, 1])))
    a = math.atan2(-r[0, 1], r[1, 1])
    c = math.atan2(-r[2, 0], r[2, 2])
    return math.degrees(a), math.degrees(b), math.degrees(c)


def _write_bvh(path: Path, problem: cp.Problem, q: np.ndarray, frame_time: float = 0.04) -> Path:
    """A BVH file of ``SKELETON`` whose joints take the body's segment orientations at each
    posture of ``q`` [rad] (frames, DOFs), its rest pose ``REST``, its axes ``AXES``."""
    body = problem.body
    dofs = {
        j: next(s.dof for s in body.segments if s.name == seg) for j, (_, seg) in SKELETON.items()
    }
    moved = [d for d in dofs.values() if d is not None]
    rotate = ca.Function("r", [body.q], [body.rotation(d) for d in moved])
    rest_q = np.zeros(body.n)
    for dof, angle in REST.items():
        rest_q[body.index[dof]] = math.radians(angle)
    rest = {d: np.array(r) for d, r in zip(moved, rotate(rest_q), strict=True)}
    lines = ["HIERARCHY"]

    def block(joint: str, depth: int) -> None:
        pad = "  " * depth
        head = "ROOT" if SKELETON[joint][0] is None else "JOINT"
        channels = "6 Xposition Yposition Zposition" if head == "ROOT" else "3"
        lines.extend([f"{pad}{head} {joint}", f"{pad}{{", f"{pad}  OFFSET 0.0 10.0 0.0"])
        lines.append(f"{pad}  CHANNELS {channels} Zrotation Xrotation Yrotation")
        children = [j for j, (p, _) in SKELETON.items() if p == joint]
        for child in children:
            block(child, depth + 1)
        if not children:
            lines.extend(
                [f"{pad}  End Site", f"{pad}  {{", f"{pad}    OFFSET 0.0 10.0 0.0", f"{pad}  }}"]
            )
        lines.append(f"{pad}}}")

    block("Hips", 0)
    lines += ["MOTION", f"Frames: {len(q)}", f"Frame Time: {frame_time}"]
    for posture in q:
        world = {d: np.array(r) for d, r in zip(moved, rotate(posture), strict=True)}
        bvh = {
            j: np.eye(3) if d is None else AXES.T @ world[d] @ rest[d].T @ AXES
            for j, d in dofs.items()
        }
        values = [0.0, 0.0, 0.0]
        for joint, (parent, _) in SKELETON.items():
            local = bvh[joint] if parent is None else bvh[parent].T @ bvh[joint]
            values += _zxy(local)
        lines.append(" ".join(f"{v:.9f}" for v in values))
    path.write_text("\n".join(lines) + "\n")
    return path


def _problem(**bvh: object) -> cp.Problem:
    joints = {j: seg for j, (_, seg) in SKELETON.items()}
    return cp.load(SEATED, {"motion.bvh": {"joints": joints, "rest_deg": REST, **bvh}})


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
    expected = _r("z", 40) @ _r("x", 50) @ _r("y", 60)
    np.testing.assert_allclose(_rotations(arm)[0], expected, atol=1e-6)
    assert np.abs(_rotations(arm)[0] - _r("x", 50) @ _r("y", 60) @ _r("z", 40)).max() > 0.1


def test_the_rest_pose_is_the_rest_posture(tmp_path: Path) -> None:
    """The body at ``REST`` (shoulders abducted 90°) is the T-pose, every channel 0; read
    back, every channel 0 is that posture."""
    problem = _problem()
    rest = np.zeros(problem.body.n)
    for dof, angle in REST.items():
        rest[problem.body.index[dof]] = math.radians(angle)
    path = _write_bvh(tmp_path / "rest.bvh", problem, np.tile(rest, (3, 1)))
    frames = path.read_text().splitlines()[-3:]
    assert all(abs(float(v)) < 1e-9 for line in frames for v in line.split())
    np.testing.assert_allclose(_read(path, problem).q, np.tile(rest, (3, 1)), atol=1e-6)


@pytest.mark.parametrize("solver", SOLVER_NAMES)
def test_a_known_motion_round_trips(solver: str, tmp_path: Path) -> None:
    """A motion of every DOF written as BVH (float channels to 1e-9°) reads back to 1e-6 rad,
    its segments on their joints' orientations, and times from the frame time."""
    problem = _problem()
    body = problem.body
    rng = np.random.default_rng(7)
    start = np.array([math.radians(0.5 * (d.lower + d.upper) / math.pi * 180) for d in body.dofs])
    steps = rng.uniform(-0.15, 0.15, size=(5, body.n))
    q = np.clip(
        start + np.cumsum(steps, axis=0),
        [d.lower + 0.2 for d in body.dofs],
        [d.upper - 0.2 for d in body.dofs],
    )
    path = _write_bvh(tmp_path / "m.bvh", problem, q, frame_time=0.04)
    recording = _read(path, cp.load(SEATED, {**problem.overrides, "posture_deg": {}}), solver)
    np.testing.assert_allclose(recording.q, q, atol=1e-6)
    np.testing.assert_allclose(recording.time, np.arange(5) * 0.04)
    assert max(r.max() for r in recording.residuals.values()) < 1e-6
    assert recording.kind == "bvh" and not recording.flags


def test_bad_mappings_are_one_line_errors(tmp_path: Path) -> None:
    problem = _problem()
    path = _write_bvh(tmp_path / "m.bvh", problem, np.zeros((2, problem.body.n)))
    wrong = _problem(joints={"RightArmm": "upper_arm_r", "Hips": "pelvis"})
    with pytest.raises(ProblemError, match="did you mean 'RightArm'"):
        _read(path, wrong)
    wrong = _problem(joints={"RightArm": "upper_arm", "Hips": "pelvis"})
    with pytest.raises(ProblemError, match="a segment of the body"):
        _read(path, wrong)
    text = tmp_path / "not.bvh"
    text.write_text("time,elbow\n0,1\n")
    with pytest.raises(ProblemError, match="starts with HIERARCHY"):
        _read(text, problem)


def test_evaluate_drives_the_body_with_a_bvh_file(tmp_path: Path) -> None:
    """The command line on a BVH file: the known angles in timeline.csv, each joint's fit
    residual per frame in degrees."""
    problem = _problem()
    body = problem.body
    q = np.tile([0.5 * (d.lower + d.upper) for d in body.dofs], (3, 1))
    q[:, body.index["elbow_flexion_r"]] = np.radians([20.0, 40.0, 60.0])
    path = _write_bvh(tmp_path / "m.bvh", problem, q, frame_time=0.5)
    joints = "\n".join(f'{j} = "{seg}"' for j, (_, seg) in SKELETON.items())
    rest = ", ".join(f"{k} = {v}" for k, v in REST.items())
    file = tmp_path / "seated.toml"
    file.write_text(
        f"{Path(SEATED).read_text()}\n[motion.bvh]\nrest_deg = {{ {rest} }}\n\n"
        f"[motion.bvh.joints]\n{joints}\n"
    )
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
