"""BVH recordings: joint rotations of an animation skeleton turned into the body's joint angles
by the package's own prioritized IK, on orientation tasks (docs/motion.md).

A BVH joint's local rotation is the product of its channels' rotations in the order the
file lists them (``Zrotation Xrotation Yrotation``: Rz·Rx·Ry); bvhio composes them. Per
frame, each joint's orientation relative to the skeleton's root, in our axes (x forward,
y left, z up, from the file's ``up`` and ``forward``), times the rest orientation of the
segment it is mapped to (the body at ``rest_deg``: the posture the skeleton has with every
channel at 0, a T-pose's arms abducted 90°), is that segment's target. One priority level
holds every target, frame axis by frame axis (least squares), the lowest the problem's
posture for what they leave free; the joint limits hold. A segment's residual is the angle
of its error rotation.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from casadi_posture.body.tree import BodyModel
from casadi_posture.errors import MISSING, ProblemError
from casadi_posture.ik.hierarchy import TaskHierarchy
from casadi_posture.ik.result import IKResult
from casadi_posture.ik.solvers import Solver, cached_solver
from casadi_posture.ik.tasks import Frame, JointReference
from casadi_posture.motion.angles import closest
from casadi_posture.motion.recording import Recording
from casadi_posture.spec.schema import MAX_DURATION_S, MAX_STEPS, BvhSpec, SolverSpec

#: Unit vectors of the axis names a file's ``up`` and ``forward`` may take.
AXES = {
    "x": (1.0, 0.0, 0.0),
    "-x": (-1.0, 0.0, 0.0),
    "y": (0.0, 1.0, 0.0),
    "-y": (0.0, -1.0, 0.0),
    "z": (0.0, 0.0, 1.0),
    "-z": (0.0, 0.0, -1.0),
}
#: The channels a BVH joint may have.
CHANNELS = ("Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation")
#: Most joints a skeleton may have (a CMU skeleton has 31, one with fingers about 70).
MAX_JOINTS = 500
#: Largest magnitude of a channel's value: degrees, or the file's length unit.
MAX_CHANNEL_VALUE = 1e5


def read_bvh(
    path: str | Path,
    body: BodyModel,
    spec: BvhSpec,
    posture: np.ndarray,
    solver_name: str,
    *,
    problem: Path,
    solver_spec: SolverSpec | None = None,
) -> Recording:
    """The BVH file ``path`` as joint angles [rad] of ``body``, by the problem file
    ``problem``'s ``[motion.bvh]`` (``spec``), ``posture`` [rad] settling what the joints
    leave free, and the IK solver ``solver_name``; each mapped segment's residual [rad]."""
    path = Path(path)
    skeleton = _read(path)
    joints = _joints(skeleton.Root)
    moving = _mapping(spec, joints, body, path, problem)
    axes = _axes(spec, problem)
    world = _world(skeleton.Root, {n: _rotations(j) for n, j in joints.items()})
    root = world[skeleton.Root.Name]
    start, rest = _rest(body, spec, [d for _, d in moving.values()])
    tasks = [Frame(f"bvh_{n}", 1, s, d, tuple(np.eye(3).ravel())) for n, (s, d) in moving.items()]
    posture_task = JointReference("posture", 2, tuple(body.dof_names), tuple(posture))
    hierarchy = TaskHierarchy(body, [*tasks, posture_task])
    solver = cached_solver(solver_name, hierarchy, solver_spec)
    frames = int(skeleton.FrameCount)
    q, residuals = np.empty((frames, body.n)), np.empty((frames, len(moving)))
    q_prev, failed = start, []
    for k in range(frames):
        # segment target = the joint's orientation relative to the root, in our axes, times
        # the segment's orientation at the skeleton's rest pose
        targets = [
            axes @ root[k].T @ world[n][k] @ axes.T @ rest[d] for n, (_, d) in moving.items()
        ]
        hierarchy.targets[: 9 * len(targets)] = np.concatenate([r.ravel("F") for r in targets])
        result = solver.solve(q_prev) if k else _first(solver, (start, posture), posture)
        q[k] = q_prev = result.q
        failed += [] if result.success else [str(k + 1)]
        residuals[k] = _angles(hierarchy, result.q, len(moving))
    time = np.arange(frames) * float(skeleton.FrameTime)
    by_joint = {n: residuals[:, j] for j, n in enumerate(moving)}
    flags = _flags(by_joint, time, spec.max_angle_residual_deg)
    if failed:
        flags.append(f"the {solver_name} IK did not converge in frame(s) {', '.join(failed[:5])}")
    note = f"BVH: {len(moving)} joints mapped, {frames} frames of {float(skeleton.FrameTime):g} s"
    return Recording(path, "bvh", time, q, (note,), tuple(flags), residuals=by_joint)


def _first(solver: Solver, starts: tuple[np.ndarray, ...], posture: np.ndarray) -> IKResult:
    """The first frame's IK answer from each of ``starts`` (the rest pose, which every
    channel measures from, and the problem's posture): a joint of three DOFs can take one
    orientation in two ways (a shoulder's flexion, abduction and rotation), and at a gimbal
    lock (a T-pose's shoulders) in many. Kept: the one that fits the joints best, then the one
    nearest ``posture`` [rad]; later frames follow from it."""
    answers = [solver.solve(np.asarray(s, dtype=float)) for s in starts]
    best = min(a.residuals[0] for a in answers)
    close = [a for a in answers if a.residuals[0] <= best + 1e-9]
    return min(close, key=lambda a: float(np.linalg.norm(a.q - posture)))


def _angles(hierarchy: TaskHierarchy, q: np.ndarray, count: int) -> np.ndarray:
    """The angle [rad] by which each of the first ``count`` segments' frames misses its
    target at ``q``: 2·asin(‖vec(R − Rt)‖ / 2√2)."""
    chords = np.asarray(hierarchy.function(q, hierarchy.targets)[0]).reshape(count, 9)
    return 2 * np.arcsin(np.clip(np.linalg.norm(chords, axis=1) / (2 * math.sqrt(2)), 0.0, 1.0))


def _mapping(
    spec: BvhSpec, joints: dict, body: BodyModel, path: Path, problem: Path
) -> dict[str, tuple[str, str]]:
    """The mapped BVH joints whose segment a DOF moves, each with its segment and that DOF
    (the last before the segment); a joint not in the
    file, a segment or a rest DOF not on the body is a one-line error naming its key."""
    if not spec.joints:
        expected = "a [motion.bvh.joints] table mapping BVH joints to the body's segments"
        raise ProblemError(problem, "motion.bvh.joints", MISSING, expected)
    segments = {s.name: s for s in body.segments}
    for name, segment in spec.joints.items():
        key = f"motion.bvh.joints.{name}"
        if name not in joints:
            expected = f"a joint of {path} ({closest(name, list(joints))})"
            raise ProblemError(problem, key, segment, expected)
        if segment not in segments:
            expected = f"a segment of the body: {closest(segment, list(segments))}"
            raise ProblemError(problem, key, segment, expected)
    for dof in spec.rest_deg:
        if dof not in body.index:
            expected = f"a DOF of the body: {closest(dof, body.dof_names)}"
            raise ProblemError(problem, f"motion.bvh.rest_deg.{dof}", dof, expected)
    moving = {
        n: (s, segments[s].dof) for n, s in spec.joints.items() if segments[s].dof is not None
    }
    if not moving:
        expected = "a BVH joint mapped to a segment the body's DOFs move"
        raise ProblemError(problem, "motion.bvh.joints", MISSING, expected)
    return moving


def _read(path: Path):
    """The file's skeleton and motion (bvhio); one-line errors for a missing or bad file."""
    try:
        import bvhio
    except ImportError:
        expected = "bvhio to read BVH files: pip install 'casadi_posture[motion]'"
        raise ProblemError(path, None, None, expected) from None
    if not path.is_file():
        raise ProblemError(path, None, None, "a BVH file that exists")
    with path.open("rb") as handle:
        head = handle.read(64)
    if not head.lstrip().upper().startswith(b"HIERARCHY"):
        raise ProblemError(path, None, None, "a BVH file (it starts with HIERARCHY)")
    _check(path)
    try:
        return bvhio.readAsBvh(str(path))
    except Exception as error:  # the parser raises several kinds on a malformed file
        raise ProblemError(path, None, None, f"a readable BVH file ({error})") from None


class _Lines:
    """A BVH file's lines that are not blank, split into words, read one after another."""

    def __init__(self, path: Path) -> None:
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as error:
            raise ProblemError(path, None, None, f"a readable BVH text file ({error})") from None
        self.path = path
        self.lines = [(n, w) for n, line in enumerate(text.splitlines(), 1) if (w := line.split())]
        self.at = 0

    def next(self, expected: str) -> tuple[int, list[str]]:
        """The next line's number and words; none left is a one-line error: ``expected``
        is missing, the file is cut short."""
        if self.at == len(self.lines):
            last = self.lines[-1][0] if self.lines else 0
            where = f"line {last + 1} (the end of the file)"
            raise ProblemError(self.path, where, MISSING, f"{expected}: the file is cut short")
        self.at += 1
        return self.lines[self.at - 1]

    def take(self, words: list[str | None], expected: str) -> list[str]:
        """The next line's words, which must be ``words`` (None: any word there)."""
        n, got = self.next(expected)
        if len(got) != len(words) or any(
            w is not None and w != g for w, g in zip(words, got, strict=True)
        ):
            raise ProblemError(self.path, f"line {n}", " ".join(got), expected)
        return got

    def error(self, expected: str, value: Any = None) -> ProblemError:
        """A one-line error on the line read last."""
        n, words = self.lines[self.at - 1]
        return ProblemError(
            self.path, f"line {n}", " ".join(words) if value is None else value, expected
        )


def _check(path: Path) -> None:
    """The BVH file ``path`` checked line by line before bvhio parses it (bvhio waits
    forever for a line past the end of a file cut short, and takes a value that is not a
    finite number): its hierarchy, at most ``MAX_JOINTS`` joints, each named once, with
    known channels; ``Frames:`` (2 to ``MAX_STEPS``) lines of frames, each with a finite
    value for every channel; a frame time [s] above 0 and within ``MAX_DURATION_S`` in all.
    Anything else is a one-line error naming the line (the frame, the joint's channel)."""
    lines = _Lines(path)
    lines.take(["HIERARCHY"], "HIERARCHY")
    channels = _hierarchy(lines)
    lines.take(["MOTION"], "MOTION, after the hierarchy's last closing brace")
    count = lines.take(["Frames:", None], "Frames: and the frame count")[1]
    frames = _number(lines, count, "the number of frames", int)
    if not 2 <= frames <= MAX_STEPS:
        raise lines.error(f"2 to {MAX_STEPS} frames", frames)
    word = lines.take(["Frame", "Time:", None], "Frame Time: and a time in s")[2]
    step = _number(lines, word, "a frame time in s")
    if not (step > 0 and (frames - 1) * step <= MAX_DURATION_S):
        expected = f"a frame time in s above 0, {frames} frames within {MAX_DURATION_S:g} s"
        raise lines.error(expected, step)
    for k in range(1, frames + 1):
        n, words = lines.next(f"frame {k} of the {frames} that Frames: says")
        _frame(lines, words, channels, f"frame {k} (line {n})")
    if lines.at < len(lines.lines):
        extra = len(lines.lines) - lines.at
        where = f"line {lines.lines[lines.at][0]}"
        expected = f"the {frames} frames that Frames: says, and no more ({extra} more line(s))"
        raise ProblemError(path, where, " ".join(lines.lines[lines.at][1])[:40], expected)


def _hierarchy(lines: _Lines) -> list[str]:
    """The skeleton's joints read from ``lines``, from ``ROOT`` to its closing brace; each
    value of a frame's line as ``<joint> <channel>``, in the file's order."""
    _, words = lines.next("ROOT and the root joint's name")
    if words[0] != "ROOT" or len(words) < 2:
        raise lines.error("ROOT and the root joint's name")
    root = words[1]
    channels: list[str] = []
    names, open_joints = {root}, [_joint(lines, root, channels)]
    while open_joints:
        _, words = lines.next(f"JOINT, End Site or a closing brace of joint {open_joints[-1]}")
        if words[0] == "JOINT" and len(words) >= 2:
            if words[1] in names or len(names) == MAX_JOINTS:
                raise lines.error(f"at most {MAX_JOINTS} joints, each named once")
            names.add(words[1])
            open_joints.append(_joint(lines, words[1], channels))
        elif words[0] == "End":  # End Site
            lines.take(["{"], "an opening brace alone on its line")
            _offset(lines)
            lines.take(["}"], "a closing brace alone on its line")
        elif words == ["}"]:
            open_joints.pop()
        else:
            raise lines.error(f"JOINT <name>, End Site or a closing brace of {open_joints[-1]}")
    return channels


def _joint(lines: _Lines, name: str, channels: list[str]) -> str:
    """A joint's opening brace, offset and channels from ``lines``, its channels added to
    ``channels``; its name."""
    lines.take(["{"], "an opening brace alone on its line")
    _offset(lines)
    _, words = lines.next(f"CHANNELS of joint {name}")
    count = -1
    if len(words) > 1 and words[0] == "CHANNELS":
        count = _number(lines, words[1], "the number of channels", int)
    if count != len(words) - 2 or not set(words[2:]) <= set(CHANNELS):
        raise lines.error(f"CHANNELS, their count and that many of {', '.join(CHANNELS)}")
    channels += [f"{name} {c}" for c in words[2:]]
    return name


def _offset(lines: _Lines) -> None:
    """An ``OFFSET`` line of three finite numbers."""
    _, words = lines.next("OFFSET and three numbers")
    if len(words) != 4 or words[0] != "OFFSET":
        raise lines.error("OFFSET and three numbers")
    for word in words[1:]:
        if not abs(_number(lines, word, "an OFFSET's number")) <= MAX_CHANNEL_VALUE:
            raise lines.error(f"a finite number within ±{MAX_CHANNEL_VALUE:g}", word)


def _number(lines: _Lines, word: str, expected: str, kind: type = float) -> Any:
    """``word`` as a number of ``kind``; one that is not is a one-line error on the line
    read last: ``expected`` was."""
    try:
        return kind(word)
    except ValueError:
        raise lines.error(expected, word) from None


def _frame(lines: _Lines, words: list[str], channels: list[str], where: str) -> None:
    """A frame's line: a finite number within ``MAX_CHANNEL_VALUE`` for each of ``channels``."""
    if len(words) != len(channels):
        expected = f"{len(channels)} values, one per channel of the hierarchy"
        raise ProblemError(lines.path, where, f"{len(words)} values", expected)
    try:
        values = np.array(words, dtype=float)
    except ValueError:
        values = np.array([_float(w) for w in words])
    bad = np.flatnonzero(~(np.abs(values) <= MAX_CHANNEL_VALUE))
    if bad.size:
        j = int(bad[0])
        expected = f"a finite number within ±{MAX_CHANNEL_VALUE:g}"
        raise ProblemError(lines.path, f"{where}, {channels[j]}", words[j], expected)


def _float(word: str) -> float:
    """``word`` as a number, NaN when it is not one."""
    try:
        return float(word)
    except ValueError:
        return math.nan


def _joints(root) -> dict:
    """Every joint of the skeleton by name, parents first."""
    out, stack = {}, [root]
    while stack:
        joint = stack.pop(0)
        out[joint.Name] = joint
        stack.extend(joint.Children)
    return out


def _rotations(joint) -> np.ndarray:
    """A joint's local rotation per frame (frames, 3, 3), its channels composed in the
    file's order."""
    from pyglm import glm

    return np.array([np.array(glm.mat3_cast(k.Rotation), dtype=float) for k in joint.Keyframes])


def _world(root: Any, local: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Each joint's orientation in the file's world per frame: its parents' local rotations
    and its own, composed from the root down."""
    out = {root.Name: local[root.Name]}
    stack = [root]
    while stack:
        joint = stack.pop(0)
        for child in joint.Children:
            out[child.Name] = out[joint.Name] @ local[child.Name]
            stack.append(child)
    return out


def _axes(spec: BvhSpec, problem: Path) -> np.ndarray:
    """The rotation from the file's axes into ours (x forward, y left, z up): its rows are
    the file's ``forward``, ``up`` × ``forward`` and ``up``."""
    up, forward = np.array(AXES[spec.up]), np.array(AXES[spec.forward])
    if abs(up @ forward) > 0.5:
        expected = "a forward axis across the up axis"
        raise ProblemError(problem, "motion.bvh.forward", spec.forward, expected)
    return np.array([forward, np.cross(up, forward), up])


def _rest(body: BodyModel, spec: BvhSpec, dofs: list[str]) -> tuple[np.ndarray, dict]:
    """The body at the skeleton's rest pose (``rest_deg``, every other DOF at 0) [rad], and
    the world orientation of each of ``dofs``' frames there."""
    q = np.zeros(body.n)
    for dof, angle in spec.rest_deg.items():
        q[body.index[dof]] = math.radians(angle)
    rotations = ca.Function("rest", [body.q], [body.rotation(d) for d in dofs]).call([q])
    return q, {d: np.asarray(r, dtype=float) for d, r in zip(dofs, rotations, strict=True)}


def _flags(residuals: dict[str, np.ndarray], time: np.ndarray, limit_deg: float) -> list[str]:
    """A flag per BVH joint whose segment misses the joint's orientation by more than
    ``limit_deg`` [deg] in some frame (``residuals`` [rad]): its worst frame, and how many."""
    out = []
    for joint, radians in residuals.items():
        values = np.degrees(radians)
        over = values > limit_deg
        if over.any():
            k = int(np.argmax(values))
            out.append(
                f"{joint}: its segment is {values[k]:.1f}° from the joint's orientation at "
                f"{time[k]:g} s "
                f"(frame {k + 1}), above motion.bvh.max_angle_residual_deg = {limit_deg:g}° in "
                f"{int(over.sum())} frame(s): the body cannot take that rotation there"
            )
    return out
