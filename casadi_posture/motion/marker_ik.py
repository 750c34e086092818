"""C3D markers turned into joint angles by the package's own prioritized IK (docs/motion.md).

Each frame, a landmark's target is the mean of its markers (``[motion.markers]``), in the
lab frame. The body's root is fixed in the world, the subject moves in the lab: a rigid
transform x = R m + t [m] brings the lab onto the body's frame. It is fitted in closed form
(Kabsch) on the landmarks fixed to the root segment (carried by no DOF) alone, at least 3
not on one line. Fitted on every landmark, the transform and the DOFs next to the root
would trade against each other (a turn of the whole subject about the ankle is a turn of
the leg's joints): the fit would be singular, or ill-conditioned and slow to alternate with
the IK. Fitted on the root's landmarks, it is what they say, and the DOFs explain the rest.
The price: the transform carries the noise of those few, close markers (a pelvis, a foot),
and the DOFs next to the root carry it on; where a joint limit stops them, the landmarks
beyond are off their markers, and flagged.

Then the IK from the last frame's posture: level 1 the other landmarks at their targets
(least squares over all of them), level 2 every DOF at the problem's posture, which only
settles what the markers leave free (a hand's turn about its own axis); joint limits are
the solver's. A landmark's residual is its distance from its target after the fit [m].

Fitted as segments (``motion.fit = "segments"``), a point's target is its markers' offset
from its anchor's, the fitted joint up its chain (an elbow from the shoulder): where the
body has fewer joints than the subject (no shoulder girdle: the acromion rises 4-5 cm as
the arm goes overhead), the segments beyond keep their measured directions instead of
reaching for their places, and the error stays on the point the body cannot follow.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from casadi_posture.body.tree import BodyModel, Landmark
from casadi_posture.errors import MISSING, ProblemError
from casadi_posture.ik.hierarchy import TaskHierarchy
from casadi_posture.ik.result import IKResult
from casadi_posture.ik.solvers import cached_solver
from casadi_posture.ik.tasks import JointReference, Offset, Position
from casadi_posture.motion.angles import closest
from casadi_posture.motion.markers import Markers, check_labels, read_c3d
from casadi_posture.motion.recording import Recording, fill_gaps
from casadi_posture.spec.schema import MotionSpec, SolverSpec

#: The root's landmarks must lie at least this far [m] (RMS) off their best line.
ROOT_SPREAD_M = 0.01
#: The lab's vertical axis named as ``motion.lab_up`` names it, in the marker file's frame.
LAB_AXES = {
    axis: tuple(sign * float(i == j) for j in range(3))
    for i, name in enumerate("xyz")
    for sign, axis in ((1, name), (-1, f"-{name}"))
}
#: Runs of frames whose residual is above the threshold flagged one by one, at most.
MAX_FLAGGED_RUNS = 10


@dataclass(frozen=True)
class MarkerFit:
    """How the body fits the markers per frame: ``residuals`` [m] (frames, landmarks), the
    distance of each landmark of ``landmarks`` from its target; the transform from the lab
    frame into the body's, x = ``rotation`` @ m + ``translation`` ((frames, 3, 3), (frames,
    3) [m])."""

    landmarks: tuple[str, ...]
    residuals: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray


def read_c3d_recording(
    source: str | Path | Markers,
    body: BodyModel,
    spec: MotionSpec,
    posture: np.ndarray,
    solver_name: str,
    *,
    problem: Path,
    solver_spec: SolverSpec | None = None,
) -> tuple[Recording, MarkerFit]:
    """The C3D file ``source`` (or its markers, read) as joint angles of ``body`` by the
    problem file ``problem``'s
    ``[motion]`` (``spec``: the marker mapping, the gap and residual limits), ``posture``
    [rad] (the lowest IK level) and the IK solver ``solver_name``."""
    if not spec.markers:
        expected = "a [motion.markers] table mapping landmarks to the C3D file's marker labels"
        raise ProblemError(problem, "motion.markers", MISSING, expected)
    return markers_to_recording(
        source if isinstance(source, Markers) else read_c3d(source),
        body,
        spec.markers,
        posture,
        solver_name,
        problem=problem,
        max_gap_s=spec.max_gap_s,
        max_residual_m=spec.max_marker_residual_m,
        solver_spec=solver_spec,
        calibration_s=None if spec.calibrate_s is None else tuple(spec.calibrate_s),
        lab_up=LAB_AXES[spec.lab_up],
        segments=spec.fit == "segments",
        clusters=spec.clusters,
    )


def markers_to_recording(
    markers: Markers,
    body: BodyModel,
    mapping: Mapping[str, Sequence[str]],
    posture: np.ndarray,
    solver_name: str,
    *,
    problem: Path | None = None,
    max_gap_s: float = 0.25,
    max_residual_m: float = 0.02,
    solver_spec: SolverSpec | None = None,
    calibration_s: tuple[float, float] | None = None,
    lab_up: Sequence[float] = (0.0, 0.0, 1.0),
    segments: bool = False,
    clusters: Mapping[str, Sequence[str]] | None = None,
) -> tuple[Recording, MarkerFit]:
    """The joint angles [rad] per frame that fit ``body``'s landmarks to the means of their
    markers (``mapping``: landmark → labels; ``problem`` names the file it came from),
    ``posture`` [rad] settling what they leave free, by the IK solver ``solver_name``.
    Marker gaps up to ``max_gap_s`` [s] are filled linearly and noted, longer ones filled and
    flagged; so are frames whose largest residual exceeds ``max_residual_m`` [m]. With
    ``calibration_s`` ([start, end] [s]: frames where the subject stands in ``posture``,
    upright along the lab's ``lab_up`` axis), each point first moves, on its segment, to
    where its markers are then (``calibrated``); a landmark of ``clusters`` (landmark → 3 or
    more labels), on which no marker sits, is placed in its markers' frame there and carried
    by them (``carried``). With ``segments``, a point is fitted relative to its anchor
    (``anchors``), the segments' directions rather than their places."""
    clusters = dict(clusters or {})
    points = _points(markers, body, mapping, problem, calibration_s is not None)
    carriers = _carriers(markers, body, clusters, points, problem, calibration_s is not None)
    names = tuple(points)
    lab, notes, flags = _targets(markers, {**points, **carriers}, max_gap_s)
    lab, on_clusters = lab[:, : len(names)], lab[:, len(names) :]
    ik = {"solver_name": solver_name, "solver_spec": solver_spec, "problem": problem}
    if calibration_s is not None:
        window = _window(markers.time, calibration_s, problem)
        still = lab[window].mean(axis=0)
        body, moved, onto_body = calibrated(
            body, still, points, posture, lab_up, problem, calibration_s
        )
        notes.append(
            f"calibrated on {calibration_s[0]:g}-{calibration_s[1]:g} s, the subject taken in "
            f"posture_deg there: markers placed on their segments, landmarks moved onto "
            f"their markers by up to {moved * 1e3:.0f} mm"
        )
        followed = carried(body, clusters, on_clusters, window, posture, onto_body)
        if clusters:
            lab = np.concatenate([lab, followed], axis=1)
            names += tuple(clusters)
    fitter = _Fitter(body, names, posture, max_residual_m, segments=segments, **ik)
    frames = markers.time.size
    q = np.empty((frames, body.n))
    residuals = np.empty((frames, len(names)))
    rotation, translation = np.empty((frames, 3, 3)), np.empty((frames, 3))
    q_prev = np.asarray(posture, dtype=float)
    failed: list[str] = []
    for k in range(frames):
        result, residuals[k], (rotation[k], translation[k]) = fitter.frame(lab[k], q_prev)
        q[k] = q_prev = result.q
        if not result.success:
            failed.append(f"{k + 1} ({result.status})")
    if failed:
        shown = ", ".join(failed[:5]) + (f" and {len(failed) - 5} more" if len(failed) > 5 else "")
        flags.append(
            f"the {solver_name} IK did not converge in frame(s) {shown}: the posture there is "
            "the best it reached"
        )
    flags += _residual_flags(residuals, markers.time, names, max_residual_m)
    source = markers.source
    by_landmark = {n: residuals[:, j] for j, n in enumerate(names)}
    recording = Recording(
        source, "c3d", markers.time, q, tuple(notes), tuple(flags), residuals=by_landmark
    )
    return recording, MarkerFit(names, residuals, rotation, translation)


class _Fitter:
    """One frame's fit of ``body``'s points ``names``: the lab onto the root's points
    (``rigid_fit``), then the IK of the others from a start, ``posture`` [rad] below, each
    at its markers or, with ``segments``, at its markers' offset from its anchor's; a frame
    whose residual exceeds ``max_residual_m`` [m] is solved again from ``posture``."""

    def __init__(
        self,
        body: BodyModel,
        names: Sequence[str],
        posture: np.ndarray,
        max_residual_m: float,
        *,
        segments: bool,
        solver_name: str,
        solver_spec: SolverSpec | None,
        problem: Path | None,
    ) -> None:
        roots = _roots(body, names, problem)
        moving = [n for n in names if n not in roots]
        self.anchors = anchors(body, names, roots) if segments else {}
        tasks = [
            Offset(f"marker_{n}", 1, n, self.anchors[n], (0.0, 0.0, 0.0))
            if n in self.anchors
            else Position(f"marker_{n}", 1, n, (0.0, 0.0, 0.0))
            for n in moving
        ]
        lowest = JointReference("posture", 2, tuple(body.dof_names), tuple(posture))
        self.hierarchy = TaskHierarchy(body, [*tasks, lowest])
        self.offsets = [self.hierarchy.offset(t) for t in tasks]
        self.solver = cached_solver(solver_name, self.hierarchy, solver_spec)
        self.posture = np.asarray(posture, dtype=float)
        self.max_residual_m = max_residual_m
        index = {n: i for i, n in enumerate(names)}
        self.rows = [index[n] for n in moving]
        self.anchor_rows = [index.get(self.anchors.get(n, ""), -1) for n in moving]
        self.root_rows = [index[n] for n in roots]
        self.at_root = np.array([body.landmarks[n].position for n in roots], dtype=float)

    def frame(
        self, lab: np.ndarray, start: np.ndarray
    ) -> tuple[IKResult, np.ndarray, tuple[np.ndarray, np.ndarray]]:
        """The IK's answer from ``start`` [rad] for the points at ``lab`` [m] (points × 3);
        each point's residual [m]; the rotation and translation of the lab onto the body."""
        rotation, translation = rigid_fit(lab[self.root_rows], self.at_root)
        at = lab @ rotation.T + translation
        origin = np.where(np.array(self.anchor_rows)[:, None] >= 0, at[self.anchor_rows], 0.0)
        for offset, target in zip(self.offsets, at[self.rows] - origin, strict=True):
            self.hierarchy.targets[offset : offset + 3] = target
        result = self.solver.solve(start)
        if result.residuals[0] > self.max_residual_m:
            # a local minimum the last frame led into (a shoulder past a gimbal lock): tried
            # again from the problem's posture, the better kept
            again = self.solver.solve(self.posture)
            result = again if again.residuals[0] < result.residuals[0] else result
        residuals = np.empty(len(lab))
        e1 = np.asarray(self.hierarchy.function(result.q, self.hierarchy.targets)[0])
        residuals[self.rows] = np.linalg.norm(e1.reshape(-1, 3), axis=1)
        residuals[self.root_rows] = np.linalg.norm(at[self.root_rows] - self.at_root, axis=1)
        return result, residuals, (rotation, translation)


def anchors(body: BodyModel, names: Sequence[str], roots: Sequence[str]) -> dict[str, str]:
    """Each fitted point's anchor, where it has one: the fitted landmark (not a root's, not
    a cluster marker) carried by the nearest DOF up its chain, the nearest of them at the
    zero posture; so an elbow hangs from a shoulder, a wrist from the elbow, a hand's
    markers from the wrist."""
    parent = {d.name: d.parent for d in body.dofs}
    dof = {n: body.landmarks[n].dof for n in names}  # a cluster's markers are placed by now
    candidates = [n for n in names if "." not in n and n not in roots]
    where = ca.Function("where", [body.q], [ca.horzcat(*[body.landmark(n) for n in names])])
    at = dict(zip(names, np.asarray(where(np.zeros(body.n))).T, strict=True))
    out = {}
    for name in names:
        up = parent.get(dof[name]) if dof[name] is not None else None
        while up is not None:
            on = [c for c in candidates if dof[c] == up]
            if on:
                out[name] = min(on, key=lambda c: float(np.linalg.norm(at[c] - at[name])))
                break
            up = parent.get(up)
    return out


def _window(time: np.ndarray, window_s: tuple[float, float], problem: Path | None) -> np.ndarray:
    """Which frames lie in ``window_s`` ([start, end] [s]); none is a one-line error."""
    inside = (time >= window_s[0] - 1e-9) & (time <= window_s[1] + 1e-9)
    if not inside.any():
        expected = f"a window of the recording's time, {time[0]:g} to {time[-1]:g} s"
        raise ProblemError(problem, "motion.calibrate_s", list(window_s), expected)
    return inside


def calibrated(
    body: BodyModel,
    still: np.ndarray,
    points: Mapping[str, Sequence[str]],
    posture: np.ndarray,
    lab_up: Sequence[float],
    problem: Path | None,
    window_s: tuple[float, float],
) -> tuple[BodyModel, float, tuple[np.ndarray, np.ndarray]]:
    """``body`` with each fitted point (``points``: a landmark, or ``<segment>.<label>``)
    placed, on the segment that carries it, at its markers'
    place ``still`` [m] (points × 3, the lab, their mean over the static window ``window_s``
    [s]), where the subject stands in ``posture`` [rad], upright: there the lab is fitted
    onto the body on the mapped landmarks, its axis ``lab_up`` kept vertical
    (``upright_fit``: the posture is known, nothing trades against it), and each point
    carried back to the zero posture through its segment's rotation; also the largest move
    of a landmark [m] and that fit (the lab onto the body: rotation, translation [m],
    x = R m + t). The markers' places on the segments are then the subject's own; a posture
    there other than ``posture`` becomes an offset of every later angle, and so do the
    landmarks' offsets from their markers through the calibration's own fit (1.3° with 1 cm
    offsets in tests/test_marker_ik.py)."""
    names = list(points)
    known = [n for n in names if n in body.landmarks]
    where = ca.Function("where", [body.q], [ca.horzcat(*[body.landmark(n) for n in known])])
    model = np.asarray(where(posture)).T
    if len(known) < 2 or np.linalg.norm(np.ptp(model[:, :2], axis=0)) < 0.01:
        expected = "at least 2 landmarks, apart horizontally, to place the markers by"
        raise ProblemError(problem, "motion.calibrate_s", list(window_s), expected)
    rotation, translation = upright_fit(still[[names.index(n) for n in known]], model, lab_up)
    placed = still @ rotation.T + translation
    segments = {s.name: s.dof for s in body.segments}
    out = {n: lm for n, lm in body.landmarks.items() if n not in points}
    dofs = [
        body.landmarks[n].dof if n in body.landmarks else segments[n.split(".")[0]] for n in names
    ]
    carried = list(dict.fromkeys(dofs))  # each DOF's frame at the posture, in one call
    frames = ca.Function(
        "frames",
        [body.q],
        [x for d in carried for x in (body.rotation(d), body.point(d, (0, 0, 0)))],
    )(posture)
    for name, dof, x in zip(names, dofs, placed, strict=True):
        k = carried.index(dof)
        r, c = (np.asarray(v, dtype=float) for v in frames[2 * k : 2 * k + 2])
        out[name] = Landmark(name, dof, tuple(r.T @ (x - c.ravel())))
    moved = np.linalg.norm(placed[[names.index(n) for n in known]] - model, axis=1).max()
    body = BodyModel(
        body.name,
        body.dofs,
        body.segments,
        list(out.values()),
        gravity=body.gravity,
        feet=body.feet,
    )
    return body, float(moved), (rotation, translation)


def carried(
    body: BodyModel,
    clusters: Mapping[str, Sequence[str]],
    lab: np.ndarray,
    window: np.ndarray,
    posture: np.ndarray,
    onto_body: tuple[np.ndarray, np.ndarray],
) -> np.ndarray:
    """Where each landmark of ``clusters`` (landmark → labels) is in the lab in each frame [m]
    (frames, landmarks, 3), carried by its markers as a rigid body (Cappozzo's cluster
    technique): in the calibration's frames ``window`` the landmark is where ``body`` has it
    at ``posture`` [rad], brought into the lab by the inverse of ``onto_body`` (the lab onto
    the body: R, t); in each frame, the markers' rigid move (``rigid_fit``) from their mean
    there carries it. ``lab`` [m] (frames, markers, 3) holds the clusters' markers in order."""
    out = np.empty((lab.shape[0], len(clusters), 3))
    if not clusters:
        return out
    rotation, translation = onto_body
    where = ca.Function("where", [body.q], [ca.horzcat(*[body.landmark(n) for n in clusters])])
    at_posture = np.asarray(where(posture)).T
    first = 0
    for j, labels in enumerate(clusters.values()):
        markers = lab[:, first : first + len(labels)]
        first += len(labels)
        still = markers[window].mean(axis=0)
        placed = (at_posture[j] - translation) @ rotation  # Rᵀ (x − t)
        for k, frame in enumerate(markers):
            r, t = rigid_fit(still, frame)
            out[k, j] = r @ placed + t
    return out


def upright_fit(
    source: np.ndarray, target: np.ndarray, up: Sequence[float]
) -> tuple[np.ndarray, np.ndarray]:
    """The rotation R and translation t [m] minimising Σ‖R sᵢ + t − tᵢ‖² over the points
    ``source`` onto ``target`` (k×3 each, k ≥ 2 apart horizontally) among the rotations
    that take the source's axis ``up`` onto the target's z: the shortest turn of ``up``
    onto z, then the best turn about z (Procrustes in the horizontal plane)."""
    u = np.asarray(up, dtype=float) / np.linalg.norm(up)
    axis, cos = np.cross(u, (0.0, 0.0, 1.0)), float(u[2])
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    tilt = np.eye(3) + k + k @ k / (1 + cos) if cos > -1 + 1e-12 else np.diag([1.0, -1.0, -1.0])
    s = (source - source.mean(axis=0)) @ tilt.T
    t = target - target.mean(axis=0)
    yaw = np.arctan2(np.sum(s[:, 0] * t[:, 1] - s[:, 1] * t[:, 0]), np.sum(s[:, :2] * t[:, :2]))
    turn = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    r = turn @ tilt
    return r, target.mean(axis=0) - r @ source.mean(axis=0)


def rigid_fit(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rotation R and translation t [m] minimising Σ‖R sᵢ + t − tᵢ‖² over the points
    ``source`` onto ``target`` (k×3 each, k ≥ 3 not on one line): Kabsch's SVD solution,
    a proper rotation (det R = +1)."""
    s_mean, t_mean = source.mean(axis=0), target.mean(axis=0)
    u, _, vt = np.linalg.svd((source - s_mean).T @ (target - t_mean))
    flip = np.diag([1.0, 1.0, np.sign(np.linalg.det(vt.T @ u.T))])
    r = vt.T @ flip @ u.T
    return r, t_mean - r @ s_mean


def _points(
    markers: Markers,
    body: BodyModel,
    mapping: Mapping[str, Sequence[str]],
    problem: Path | None,
    calibrating: bool,
) -> dict[str, list[str]]:
    """The points the IK fits, each with the markers whose mean it is: a landmark of the
    body with its markers; a segment's markers each a point of its own on that segment
    (``<segment>.<label>``, placed by the calibration). A key that is neither, a segment
    without a calibration, a label not in the file (or in it twice) is a one-line error."""
    segments = {s.name for s in body.segments}
    points: dict[str, list[str]] = {}
    for name, labels in mapping.items():
        key = f"motion.markers.{name}"
        if name not in body.landmarks and name not in segments:
            choices = [*body.landmarks, *segments]
            expected = f"a landmark or a segment of the body: {closest(name, choices)}"
            raise ProblemError(problem, key, name, expected)
        if name not in body.landmarks and not calibrating:
            expected = "a landmark: a segment's markers are placed by motion.calibrate_s"
            raise ProblemError(problem, key, name, expected)
        check_labels(markers, {name: labels}, "motion.markers", problem)
        if name in body.landmarks:
            points[name] = list(labels)
        else:
            points.update({f"{name}.{label}": [label] for label in labels})
    return points


def _carriers(
    markers: Markers,
    body: BodyModel,
    clusters: Mapping[str, Sequence[str]],
    points: Mapping[str, Sequence[str]],
    problem: Path | None,
    calibrating: bool,
) -> dict[str, list[str]]:
    """Each marker of ``clusters`` (landmark → labels) as a point of its own, for its gaps
    to be filled; a cluster without a calibration, on a landmark the body has not or one
    mapped already, with a label not in the file, or with fewer than 3 markers not on one
    line in the first frame they are all seen, is a one-line error."""
    out: dict[str, list[str]] = {}
    for name, labels in clusters.items():
        key = f"motion.clusters.{name}"
        if not calibrating:
            expected = "motion.calibrate_s too: a cluster's landmark is placed there"
            raise ProblemError(problem, key, name, expected)
        if name not in body.landmarks or name in points:
            close = closest(name, list(body.landmarks))
            expected = f"a landmark of the body not in motion.markers: {close}"
            raise ProblemError(problem, key, name, expected)
        check_labels(markers, {name: labels}, "motion.clusters", problem)
        xyz = np.stack([markers.marker(label) for label in labels], axis=1)
        seen = np.flatnonzero(np.isfinite(xyz).all(axis=(1, 2)))
        first = xyz[seen[0]] if seen.size else np.zeros((len(labels), 3))
        spread = np.linalg.svd(first - first.mean(axis=0), compute_uv=False)
        if spread[1] < ROOT_SPREAD_M * np.sqrt(len(labels)):
            expected = (
                "3 or more markers, not on one line, seen together in one frame at least of "
                f"{markers.source}"
            )
            raise ProblemError(problem, key, list(labels), expected)
        out.update({f"{name}:{label}": [label] for label in labels})
    return out


def _roots(body: BodyModel, names: Sequence[str], problem: Path | None) -> list[str]:
    """The fitted points fixed to the body's root; fewer than 3, or on one line, or all of
    them, is a one-line error."""
    fixed = [n for n, lm in body.landmarks.items() if lm.dof is None]
    roots = [n for n in names if n in fixed]
    points = np.array([body.landmarks[n].position for n in roots], dtype=float).reshape(-1, 3)
    spread = np.linalg.svd(points - points.mean(axis=0), compute_uv=False) if roots else [0.0]
    if len(roots) < 3 or spread[1] / np.sqrt(len(roots)) < ROOT_SPREAD_M:
        shown = ", ".join(n for n in fixed if "." not in n)
        expected = (
            f"at least 3 points fixed to the body's root, not on one line ({shown}, or the "
            f"root segment's markers; mapped: {', '.join(roots) or 'none'}): the transform "
            "from the lab into the body's frame is fitted on them"
        )
        raise ProblemError(problem, "motion.markers", MISSING, expected)
    if len(roots) == len(names):
        expected = "a landmark moved by the body's DOFs too (all mapped ones are on its root)"
        raise ProblemError(problem, "motion.markers", MISSING, expected)
    return roots


def _targets(
    markers: Markers, mapping: Mapping[str, Sequence[str]], max_gap_s: float
) -> tuple[np.ndarray, list[str], list[str]]:
    """Each landmark's target in the lab [m] (frames, landmarks, 3), the mean of its markers
    with their gaps filled (``fill_gaps``), and the notes and flags on the gaps."""
    time = markers.time
    filled: dict[str, np.ndarray] = {}
    short_runs, flags = 0, []
    for label in dict.fromkeys(label for labels in mapping.values() for label in labels):
        try:
            xyz = [fill_gaps(c, time, max_gap_s) for c in markers.marker(label).T]
        except ValueError:
            expected = f"a marker seen in at least one frame (missing from all {time.size})"
            raise ProblemError(markers.source, label, MISSING, expected) from None
        filled[label] = np.column_stack([c[0] for c in xyz])
        _, short, long = xyz[0]
        short_runs += len(short)
        for first, last in long:
            flags.append(
                f"marker {label}: frames {first + 1}-{last + 1} ({time[first]:g}-{time[last]:g} s) "
                f"missing for longer than motion.max_gap_s = {max_gap_s:g} s, filled linearly: "
                "the posture there is not measured"
            )
    notes = []
    if short_runs:
        notes.append(
            f"{short_runs} marker gap(s) of at most {max_gap_s:g} s filled by linear "
            "interpolation; no frame skipped"
        )
    lab = np.stack([np.mean([filled[m] for m in labels], axis=0) for labels in mapping.values()])
    return lab.transpose(1, 0, 2), notes, flags


def _residual_flags(
    residuals: np.ndarray, time: np.ndarray, names: tuple[str, ...], limit_m: float
) -> list[str]:
    """A flag per run of frames whose largest landmark residual exceeds ``limit_m`` [m],
    naming its worst frame and landmark (at most ``MAX_FLAGGED_RUNS``, then a count)."""
    worst = residuals.max(axis=1)
    over = np.diff(np.concatenate(([0], (worst > limit_m).astype(int), [0])))
    runs = list(zip(np.flatnonzero(over == 1), np.flatnonzero(over == -1) - 1, strict=True))
    flags = []
    for first, last in runs[:MAX_FLAGGED_RUNS]:
        k = first + int(np.argmax(worst[first : last + 1]))
        where, worst_of_run = f"frame {first + 1} ({time[first]:g} s)", ""
        if last > first:
            where = f"frames {first + 1}-{last + 1} ({time[first]:g}-{time[last]:g} s)"
            worst_of_run = f" in frame {k + 1}, the worst of them"
        flags.append(
            f"{where}: {names[int(np.argmax(residuals[k]))]} {worst[k] * 1e3:.1f} mm from its "
            f"markers{worst_of_run}, above motion.max_marker_residual_m = {limit_m * 1e3:g} mm: "
            "the markers do not fit the body there"
        )
    if len(runs) > MAX_FLAGGED_RUNS:
        more = len(runs) - MAX_FLAGGED_RUNS
        flags.append(f"{more} more run(s) of frames with a landmark above {limit_m * 1e3:g} mm")
    return flags
