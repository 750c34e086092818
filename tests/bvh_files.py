"""BVH files of a known motion for the tests: a skeleton of the seated body's trunk and arms,
written from postures of the body (``write_bvh``), and the problem that maps it."""

from __future__ import annotations

import math
from pathlib import Path

import casadi as ca
import numpy as np

import casadi_posture as cp

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


def rotation(axis: str, degrees: float) -> np.ndarray:
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


def write_bvh(path: Path, problem: cp.Problem, q: np.ndarray, frame_time: float = 0.04) -> Path:
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


def bvh_problem(**bvh: object) -> cp.Problem:
    joints = {j: seg for j, (_, seg) in SKELETON.items()}
    return cp.load(SEATED, {"motion.bvh": {"joints": joints, "rest_deg": REST, **bvh}})


def bvh_problem_file(path: Path) -> Path:
    """The seated problem with the ``[motion.bvh]`` of ``bvh_problem``, written to ``path``."""
    joints = "\n".join(f'{j} = "{seg}"' for j, (_, seg) in SKELETON.items())
    rest = ", ".join(f"{k} = {v}" for k, v in REST.items())
    path.write_text(
        f"{Path(SEATED).read_text()}\n[motion.bvh]\nrest_deg = {{ {rest} }}\n\n"
        f"[motion.bvh.joints]\n{joints}\n"
    )
    return path
