"""C3D marker recordings read and turned into joint angles by the prioritized IK."""

from __future__ import annotations

import csv
import sys
from collections.abc import Callable
from pathlib import Path

import casadi as ca
import ezc3d
import numpy as np
import pytest
from click.testing import CliRunner
from recording_fuzzing import BOX, evaluate, invoke, problems, short_c3d

import casadi_posture as cp
from casadi_posture.body.tree import BodyModel
from casadi_posture.cli import main
from casadi_posture.errors import ProblemError
from casadi_posture.ik.solvers import SOLVER_NAMES
from casadi_posture.ik.tasks import rotation_rpy
from casadi_posture.motion.marker_ik import (
    anchors,
    markers_to_recording,
    read_c3d_recording,
    rigid_fit,
    upright_fit,
)
from casadi_posture.motion.markers import Markers, read_c3d

SEATED = "problems/seated_assembly.toml"
STANDING = "problems/standing_wall_horizontal.toml"
#: The landmarks mapped, each to one marker named after it, but the elbows: two markers
#: 3 cm either side of the joint along the body's y axis, whose mean it is.
LANDMARKS = (
    "mid_hip", "l5s1", "hip_r", "hip_l", "c7", "vertex", "eyes", "shoulder_r", "shoulder_l",
    "elbow_r", "elbow_l", "wrist_r", "wrist_l", "grip_r", "grip_l", "knuckles_r", "knuckles_l",
)  # fmt: skip
EPICONDYLE = np.array([0.0, 0.03, 0.0])
#: The known posture [deg] of frame 1 (others from the problem's posture_deg); each DOF
#: listed turns 1.5° more per frame. Within the ranges, the elbows bent (shoulder rotation
#: then shows in the wrists), the hands straight (their turn about their axis is the
#: problem's posture, which the lowest IK level holds).
MOVED_DEG = {
    "lumbar_flexion": 15.0, "lumbar_bending": 5.0, "lumbar_rotation": -10.0,
    "shoulder_flexion_r": 40.0, "shoulder_abduction_r": 20.0, "shoulder_rotation_r": 10.0,
    "elbow_flexion_r": 60.0, "shoulder_flexion_l": 30.0, "shoulder_abduction_l": 15.0,
    "shoulder_rotation_l": -10.0, "elbow_flexion_l": 45.0,
}  # fmt: skip
#: And on the standing body, the legs (the left knee bent: the hip's rotation then shows).
STANDING_DEG = {
    "ankle_inversion_r": 3.0, "ankle_flexion_r": 5.0, "knee_flexion_r": 10.0,
    "hip_rotation_r": 5.0, "hip_abduction_r": 4.0, "hip_flexion_r": 12.0,
    "hip_flexion_l": 20.0, "hip_abduction_l": 5.0, "hip_rotation_l": -5.0,
    "knee_flexion_l": 25.0, "ankle_flexion_l": -10.0, "ankle_inversion_l": 4.0,
}  # fmt: skip
FRAMES, RATE_HZ = 4, 100.0
#: The lab frame: body = R · lab + t.
R_LAB = rotation_rpy(0.1, -0.2, 2.5)
T_LAB = np.array([0.1, -0.2, 0.9])


@pytest.fixture(scope="module")
def seated() -> cp.Problem:
    return cp.load(SEATED)


def _motion(problem: cp.Problem, moved_deg: dict[str, float]) -> np.ndarray:
    """Postures [rad] of ``FRAMES`` frames: the problem's, but the DOFs of ``moved_deg`` at
    their angle [deg] in frame 1 and 1.5° more in each frame after, within their range."""
    body, q = problem.body, np.tile(problem.posture, (FRAMES, 1))
    for dof, angle in moved_deg.items():
        q[:, body.index[dof]] = np.radians(angle + 1.5 * np.arange(FRAMES))
    assert np.all((q > body.lower + 0.1) & (q < body.upper - 0.1))
    return q


def _in_lab(body: BodyModel, names: tuple[str, ...], q: np.ndarray) -> np.ndarray:
    """The landmarks ``names`` at postures ``q`` [rad] seen from the lab [m] (frames,
    landmarks, 3)."""
    at = ca.Function("at", [body.q], [ca.horzcat(*[body.landmark(n) for n in names]).T])
    return np.array([(np.asarray(at(qk)) - T_LAB) @ R_LAB for qk in q])


def _labels() -> tuple[list[str], dict[str, list[str]]]:
    mapping = {n: [n.upper()] for n in LANDMARKS}
    mapping["elbow_r"] = ["EPIC_R_LAT", "EPIC_R_MED"]
    mapping["elbow_l"] = ["EPIC_L_MED", "EPIC_L_LAT"]
    return [m for labels in mapping.values() for m in labels], mapping


def _lab_markers(problem: cp.Problem, q: np.ndarray) -> np.ndarray:
    """The markers [m] in the lab (frames, markers, 3), in the order of ``_labels``, from
    the body's landmarks at postures ``q`` [rad]."""
    x = _in_lab(problem.body, LANDMARKS, q)
    columns = []
    for i, name in enumerate(LANDMARKS):
        offset = EPICONDYLE @ R_LAB if "elbow" in name else None
        columns += [x[:, i]] if offset is None else [x[:, i] - offset, x[:, i] + offset]
    return np.stack(columns, axis=1)


def _write_c3d(path: Path, labels: list[str], lab_m: np.ndarray, units: str = "mm") -> Path:
    """``lab_m`` [m] (frames, markers, 3) written in ``units`` with ezc3d (NaN: not seen)."""
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = [RATE_HZ]
    c3d["parameters"]["POINT"]["LABELS"]["value"] = labels
    c3d.add_parameter("POINT", "UNITS", [units])
    points = np.ones((4, len(labels), lab_m.shape[0]))
    points[:3] = lab_m.transpose(2, 1, 0) / {"mm": 1e-3, "cm": 1e-2, "m": 1.0}.get(units, 1.0)
    c3d["data"]["points"] = points
    c3d.write(str(path))
    return path


@pytest.fixture(scope="module")
def recorded(seated: cp.Problem, tmp_path_factory: pytest.TempPathFactory) -> tuple:
    """The known motion, its markers in the lab and the C3D file holding them in mm."""
    q = _motion(seated, MOVED_DEG)
    labels, mapping = _labels()
    lab = _lab_markers(seated, q)
    path = _write_c3d(tmp_path_factory.mktemp("c3d") / "seated.c3d", labels, lab)
    return q, lab, mapping, path


def _read(path: Path, problem: cp.Problem, solver: str):
    """The C3D file as the problem's joint angles, as evaluate reads it."""
    return read_c3d_recording(
        path,
        problem.body,
        problem.spec.motion,
        problem.posture,
        solver,
        problem=problem.path,
        solver_spec=problem.spec.solver,
    )


def _problem(mapping: dict[str, list[str]]) -> cp.Problem:
    return cp.load(SEATED, {"motion.markers": mapping})


def _error(call: Callable[..., object], *args: object) -> str:
    """The one-line message of the ProblemError ``call(*args)`` raises."""
    with pytest.raises(ProblemError) as caught:
        call(*args)
    message = str(caught.value)
    assert "\n" not in message
    return message


@pytest.mark.parametrize("solver", SOLVER_NAMES)
def test_markers_of_a_known_motion_give_back_its_angles_and_the_lab_transform(
    seated: cp.Problem, recorded: tuple, solver: str
) -> None:
    q, lab, mapping, path = recorded
    recording, fit = _read(path, _problem(mapping), solver)
    assert recording.kind == "c3d" and recording.source == path
    np.testing.assert_allclose(recording.time, np.arange(FRAMES) / RATE_HZ)
    # A C3D file holds float32: 0.7 m in mm to about 3e-8 m.
    assert np.abs(recording.q - q).max() < 1e-6
    assert np.abs(fit.rotation - R_LAB).max() < 1e-6
    assert np.abs(fit.translation - T_LAB).max() < 1e-6
    assert fit.landmarks == tuple(mapping) and fit.residuals.shape == (FRAMES, len(mapping))
    assert fit.residuals.max() < 1e-6
    assert recording.notes == () and recording.flags == ()
    exact = Markers(path, recording.time, tuple(_labels()[0]), lab)
    recording, fit = markers_to_recording(exact, seated.body, mapping, seated.posture, solver)
    assert np.abs(recording.q - q).max() < 1e-7
    assert np.abs(fit.rotation - R_LAB).max() < 1e-12
    assert np.abs(fit.translation - T_LAB).max() < 1e-12


@pytest.mark.parametrize("solver", SOLVER_NAMES)
def test_the_standing_body_is_fitted_on_its_right_foot_and_recovered(solver: str) -> None:
    problem = cp.load(STANDING)
    body = problem.body
    names = tuple(body.landmarks)
    q = _motion(problem, MOVED_DEG | STANDING_DEG)
    markers = Markers(
        Path("standing.c3d"), np.arange(FRAMES) / RATE_HZ, names, _in_lab(body, names, q)
    )
    recording, fit = markers_to_recording(
        markers, body, {n: [n] for n in names}, problem.posture, solver
    )
    assert np.abs(recording.q - q).max() < 1e-7
    assert np.abs(fit.rotation - R_LAB).max() < 1e-12
    assert np.abs(fit.translation - T_LAB).max() < 1e-12
    assert fit.residuals.max() < 1e-8 and recording.flags == ()


@pytest.mark.parametrize(("units", "metres"), [("mm", 1e-3), ("cm", 1e-2), ("m", 1.0)])
def test_c3d_points_are_read_in_metres_and_a_point_not_seen_is_nan(
    tmp_path: Path, units: str, metres: float
) -> None:
    written = np.arange(2 * 3 * 3, dtype=float).reshape(2, 3, 3) + 1.0
    written[1, 2] = np.nan
    written[0, 1] = 0.0
    c3d = ezc3d.c3d()
    c3d["header"]["points"]["first_frame"] = 9
    c3d["parameters"]["POINT"]["RATE"]["value"] = [50.0]
    c3d["parameters"]["POINT"]["LABELS"]["value"] = ["A", "B", "C"]
    c3d.add_parameter("POINT", "UNITS", [units])
    c3d["data"]["points"] = np.concatenate([written.transpose(2, 1, 0), np.ones((1, 3, 2))])
    c3d.write(str(tmp_path / "units.c3d"))
    markers = read_c3d(tmp_path / "units.c3d")
    assert markers.labels == ("A", "B", "C")
    np.testing.assert_allclose(markers.time, [9 / 50, 10 / 50])
    expected = written * metres
    expected[0, 1] = np.nan
    np.testing.assert_allclose(markers.positions, expected, rtol=1e-6)


def test_a_marker_moved_5_cm_in_one_frame_is_flagged_with_its_frame_and_landmark(
    seated: cp.Problem, recorded: tuple, tmp_path: Path
) -> None:
    q, lab, mapping, _ = recorded
    labels, _ = _labels()
    moved = lab.copy()
    moved[2, labels.index("VERTEX")] += R_LAB.T @ [0.0, 0.0, 0.05]
    path = _write_c3d(tmp_path / "moved.c3d", labels, moved)
    recording, fit = _read(path, _problem(mapping), "nullspace")
    vertex = list(mapping).index("vertex")
    assert fit.residuals[2, vertex] > 0.02
    assert np.delete(fit.residuals, 2, axis=0).max() < 1e-6
    (flag,) = recording.flags
    assert flag.startswith(f"frame 3 (0.02 s): vertex {fit.residuals[2, vertex] * 1e3:.1f} mm")
    assert np.abs(np.delete(recording.q - q, 2, axis=0)).max() < 1e-6


@pytest.mark.parametrize("solver", SOLVER_NAMES)
def test_markers_of_an_elbow_bent_backwards_leave_it_at_its_limit(
    seated: cp.Problem, solver: str
) -> None:
    q = _motion(seated, MOVED_DEG)
    elbow = seated.body.index["elbow_flexion_r"]
    q[:, elbow] = np.radians(-20.0)
    labels, mapping = _labels()
    markers = Markers(
        Path("x.c3d"), np.arange(FRAMES) / RATE_HZ, tuple(labels), _lab_markers(seated, q)
    )
    recording, fit = markers_to_recording(markers, seated.body, mapping, seated.posture, solver)
    assert np.all(recording.q >= seated.body.lower) and np.all(recording.q <= seated.body.upper)
    np.testing.assert_allclose(recording.q[:, elbow], seated.body.lower[elbow], atol=1e-6)
    assert fit.residuals[:, list(mapping).index("wrist_r")].min() > 0.005
    assert any(f.startswith("frames 1-4 (0-0.03 s): elbow_r ") for f in recording.flags)


def test_a_short_marker_gap_is_filled_and_noted_a_long_one_flagged(
    seated: cp.Problem, recorded: tuple, tmp_path: Path
) -> None:
    q, lab, mapping, _ = recorded
    labels, _ = _labels()
    gap = lab.copy()
    gap[1, labels.index("WRIST_R")] = np.nan
    path = _write_c3d(tmp_path / "gap.c3d", labels, gap)
    markers = read_c3d(path)
    assert np.isnan(markers.marker("WRIST_R")[1]).all() and np.isfinite(markers.positions[0]).all()
    body = seated.body
    recording, _ = markers_to_recording(markers, body, mapping, seated.posture, "nullspace")
    assert recording.notes == (
        "1 marker gap(s) of at most 0.25 s filled by linear interpolation; no frame skipped",
    )
    assert recording.flags == ()
    assert np.abs(recording.q[[0, 2, 3]] - q[[0, 2, 3]]).max() < 1e-6
    recording, _ = markers_to_recording(
        markers, body, mapping, seated.posture, "nullspace", max_gap_s=0.01
    )
    assert recording.notes == ()
    (flag,) = recording.flags
    assert flag.startswith("marker WRIST_R: frames 2-2 (0.01-0.01 s) missing for longer than")
    gap[:, labels.index("WRIST_R")] = np.nan
    unseen = read_c3d(_write_c3d(tmp_path / "unseen.c3d", labels, gap))
    message = _error(markers_to_recording, unseen, body, mapping, seated.posture, "nullspace")
    expected = "a marker seen in at least one frame (missing from all 4)"
    assert message == f"{unseen.source}: WRIST_R: expected {expected}"


def test_the_rigid_fit_finds_a_known_rotation_and_translation() -> None:
    points = np.array([[0.0, 0.0, 0.0], [0.3, 0.0, 0.1], [0.0, 0.2, 0.0], [0.1, 0.1, 0.4]])
    r, t = rigid_fit(points, points @ R_LAB.T + T_LAB)
    np.testing.assert_allclose(r, R_LAB, atol=1e-12)
    np.testing.assert_allclose(t, T_LAB, atol=1e-12)
    assert np.linalg.det(r) == pytest.approx(1.0)


def test_the_upright_fit_keeps_the_lab_vertical_and_finds_the_turn_about_it() -> None:
    """A lab whose vertical is its y axis (an OptiTrack habit): points turned by a known
    rotation that takes y onto z give it back; with the points moved off that rotation
    (a bent arm where the body's is straight), the lab's vertical still lands on z exactly
    where a free fit (Kabsch) tilts it."""
    to_z = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])  # y -> z
    yaw = rotation_rpy(0.0, 0.0, 2.0)
    truth = yaw @ to_z
    points = np.array([[0.0, 0.0, 0.0], [0.3, 0.5, 0.1], [0.0, 0.2, 0.4], [0.1, 1.1, 0.4]])
    r, t = upright_fit(points, points @ truth.T + T_LAB, (0.0, 1.0, 0.0))
    np.testing.assert_allclose(r, truth, atol=1e-12)
    np.testing.assert_allclose(t, T_LAB, atol=1e-12)
    bent = points @ truth.T + T_LAB + np.array([[0, 0, 0], [0.1, 0, 0.2], [0, 0, 0], [0, 0.1, 0]])
    r, _ = upright_fit(points, bent, (0.0, 1.0, 0.0))
    np.testing.assert_allclose(r @ (0.0, 1.0, 0.0), (0.0, 0.0, 1.0), atol=1e-12)
    free, _ = rigid_fit(points, bent)
    assert np.linalg.norm(free @ (0.0, 1.0, 0.0) - (0.0, 0.0, 1.0)) > 0.05
    r, _ = upright_fit(points, points @ np.diag([1.0, -1.0, -1.0]).T, (0.0, 0.0, -1.0))
    np.testing.assert_allclose(r, np.diag([1.0, -1.0, -1.0]), atol=1e-12)  # upside down


def test_anchors_hang_each_point_from_the_nearest_fitted_joint_up_its_chain(
    seated: cp.Problem,
) -> None:
    names = ("mid_hip", "l5s1", "hip_r", "c7", "shoulder_r", "elbow_r", "wrist_r", "knuckles_r")
    got = anchors(seated.body, names, ("mid_hip", "l5s1", "hip_r"))
    assert got == {"elbow_r": "shoulder_r", "wrist_r": "elbow_r", "knuckles_r": "wrist_r"}
    got = anchors(seated.body, ("mid_hip", "l5s1", "hip_r", "c7", "wrist_r"), ("mid_hip",))
    assert got == {"wrist_r": "c7"}  # no elbow mapped: the next joint up that is


@pytest.mark.parametrize("solver", SOLVER_NAMES)
def test_fitting_segments_gives_the_arm_back_when_the_shoulder_rises(
    seated: cp.Problem, solver: str
) -> None:
    """The right shoulder and everything beyond it 4 cm higher than the body has them (a
    shoulder girdle elevated, which the body has not). Fitted as segments (each point from
    its anchor), the elbow, wrist and hand come back to 1e-5 rad and fit exactly; only the
    raised shoulder point is off (37 mm: it turns the trunk a little, 4°, which the shoulder
    angles take back). Fitted as positions, the arm reaches for the raised points: the
    elbow 3° off, the shoulder 9°, every arm point off."""
    body = seated.body
    names = ("mid_hip", "l5s1", "hip_r", "hip_l", "c7", "vertex", "shoulder_r", "elbow_r",
             "wrist_r", "knuckles_r")  # fmt: skip
    q = _motion(seated, MOVED_DEG)
    world = _in_lab(body, names, q) @ R_LAB.T + T_LAB
    world[:, 6:] += (0.0, 0.0, 0.04)
    markers = Markers(Path("raised.c3d"), np.arange(FRAMES) / RATE_HZ, names, world)
    args = (markers, body, {n: [n] for n in names}, seated.posture, solver)
    distal = [body.index[d] for d in ("elbow_flexion_r", "wrist_flexion_r", "wrist_deviation_r")]
    shoulder = [body.index[f"shoulder_{d}_r"] for d in ("flexion", "abduction", "rotation")]
    recording, fit = markers_to_recording(*args, segments=True, max_residual_m=0.05)
    np.testing.assert_allclose(recording.q[:, distal], q[:, distal], atol=1e-5)  # IPOPT's tol
    assert fit.residuals[:, 7:].max() < 1e-6
    assert 0.03 < fit.residuals[:, 6].min() <= fit.residuals[:, 6].max() < 0.04
    positions, by_position = markers_to_recording(*args, max_residual_m=0.05)
    assert np.degrees(np.abs(positions.q[:, distal] - q[:, distal]).max()) > 2.0
    assert by_position.residuals[:, 7:].min() > 2e-3

    def worst(got: np.ndarray) -> float:
        return float(np.degrees(np.abs(got[:, shoulder] - q[:, shoulder]).max()))

    assert worst(recording.q) < 0.5 * worst(positions.q)


def test_a_landmark_carried_by_a_cluster_follows_it(seated: cp.Problem) -> None:
    """Three markers around the right shoulder, rigid with it, and no marker on the
    shoulder itself (a joint centre): placed in their frame at the calibration (frame 1,
    the subject in posture_deg), the shoulder then goes where they take it. The shoulder,
    cluster and arm raised 4 cm after frame 1 (an elevated girdle, which the body has not):
    the carried shoulder is the 4 cm off the body's, and fitted as segments the arm comes
    back to 1e-5 rad."""
    body = seated.body
    names = ("mid_hip", "l5s1", "hip_r", "hip_l", "c7", "vertex", "shoulder_r", "elbow_r",
             "wrist_r", "knuckles_r")  # fmt: skip
    q = np.vstack([seated.posture, _motion(seated, MOVED_DEG)])
    world = _in_lab(body, names, q) @ R_LAB.T + T_LAB
    turn = ca.Function("turn", [body.q], [body.rotation(body.landmarks["shoulder_r"].dof)])
    around = np.array([[0.03, 0.0, 0.04], [-0.04, -0.02, 0.03], [0.0, -0.05, 0.0]])
    cluster = np.array([world[k, 6] + around @ np.asarray(turn(qk)).T for k, qk in enumerate(q)])
    world[1:, 6:] += (0.0, 0.0, 0.04)
    cluster[1:] += (0.0, 0.0, 0.04)
    labels = (*[n for n in names if n != "shoulder_r"], "AC1", "AC2", "AC3")
    points = np.concatenate([np.delete(world, 6, axis=1), cluster], axis=1)
    lab = (points - T_LAB) @ R_LAB
    markers = Markers(Path("cluster.c3d"), np.arange(len(q)) / RATE_HZ, labels, lab)
    mapping = {n: [n] for n in names if n != "shoulder_r"}
    up = R_LAB.T @ (0.0, 0.0, 1.0)
    args = (markers, body, mapping, seated.posture, "nullspace")
    kwargs = {"calibration_s": (0.0, 0.0), "lab_up": up, "max_residual_m": 0.05}
    clusters = {"shoulder_r": ["AC1", "AC2", "AC3"]}
    recording, fit = markers_to_recording(*args, segments=True, clusters=clusters, **kwargs)
    assert fit.landmarks[-1] == "shoulder_r"
    np.testing.assert_allclose(fit.residuals[0, -1], 0.0, atol=1e-9)
    assert 0.03 < fit.residuals[1:, -1].min() <= fit.residuals[1:, -1].max() < 0.04
    distal = [body.index[d] for d in ("elbow_flexion_r", "wrist_flexion_r", "wrist_deviation_r")]
    np.testing.assert_allclose(recording.q[:, distal], q[:, distal], atol=1e-5)
    for wrong, match in (
        ({"shoulder_r": ["AC1", "AC2", "AC9"]}, "AC9"),
        ({"elbow_r": ["AC1", "AC2", "AC3"]}, "not in motion.markers"),
        ({"shoulder_x": ["AC1", "AC2", "AC3"]}, "shoulder_x"),
    ):
        with pytest.raises(ProblemError, match=match):
            markers_to_recording(*args, clusters=wrong, **kwargs)
    with pytest.raises(ProblemError, match="calibrate_s"):
        markers_to_recording(*args, clusters=clusters)
    line = Markers(markers.source, markers.time, labels, lab.copy())
    line.positions[:, -1] = 2 * line.positions[:, -2] - line.positions[:, -3]  # on AC1-AC2
    with pytest.raises(ProblemError, match="not on one line"):
        markers_to_recording(
            line, body, mapping, seated.posture, "nullspace", clusters=clusters, **kwargs
        )


def test_a_mapping_that_does_not_fit_the_body_or_the_file_is_a_one_line_error(
    recorded: tuple,
) -> None:
    _, _, mapping, path = recorded
    wrong = {**mapping, "elbw_r": mapping["elbow_r"]}
    message = _error(_read, path, _problem(wrong), "nullspace")
    assert message.startswith(f"{SEATED}: motion.markers.elbw_r = 'elbw_r': expected")
    assert "did you mean 'elbow_r'?" in message
    absent = {**mapping, "elbow_r": ["EPIC_R_LAT", "EPIC_R_MEDIAL"]}
    message = _error(_read, path, _problem(absent), "nullspace")
    assert message.startswith(f"{SEATED}: motion.markers.elbow_r = 'EPIC_R_MEDIAL': expected")
    assert f"a marker label of {path}" in message and "did you mean 'EPIC_R_MED'?" in message
    no_root = {k: v for k, v in mapping.items() if k not in ("l5s1", "hip_r", "hip_l")}
    message = _error(_read, path, _problem(no_root), "nullspace")
    assert "at least 3 points fixed to the body's root" in message
    assert "mapped: mid_hip)" in message
    message = _error(cp.load, SEATED, {"motion.markers": {"c7": ["C7"], "eyes": ["EYES"]}})
    expected = "at least 3 landmarks, each mapped to a list of marker labels"
    assert message == f"{SEATED}: motion.markers: expected {expected}"


def test_a_file_that_is_not_c3d_or_has_unknown_units_is_a_one_line_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    text = tmp_path / "angles.c3d"
    text.write_text("time_s,elbow_flexion\n0,10\n1,20\n" * 40)
    assert "a C3D file (this one is not" in _error(read_c3d, text)
    assert "a readable C3D file" in _error(read_c3d, tmp_path / "absent.c3d")
    inches = _write_c3d(tmp_path / "inches.c3d", ["A"], np.ones((2, 1, 3)), units="in")
    message = _error(read_c3d, inches)
    assert message == f"{inches}: POINT:UNITS = 'in': expected one of ['mm', 'cm', 'm']"
    empty = _write_c3d(tmp_path / "empty.c3d", [], np.ones((2, 0, 3)))
    assert "with marker points (it has none)" in _error(read_c3d, empty)
    monkeypatch.setitem(sys.modules, "ezc3d", None)
    assert "pip install 'casadi_posture[motion]'" in _error(read_c3d, inches)


def test_evaluate_drives_the_body_with_a_c3d_file(recorded: tuple, tmp_path: Path) -> None:
    """The command line on the C3D file: the known angles in timeline.csv (to the file's
    float32 storage), each landmark's residual per frame, the part held in its window only."""
    q, _, mapping, path = recorded
    problem = tmp_path / "seated.toml"
    text = Path(SEATED).read_text()
    table = "\n".join(f"{k} = {v!r}".replace("'", '"') for k, v in mapping.items())
    problem.write_text(
        f"{text}\n[motion]\nheld_s = {{ part = [[0.0, 0.015]] }}\n\n[motion.markers]\n{table}\n"
    )
    out = tmp_path / "out"
    result = CliRunner().invoke(
        main, ["evaluate", str(problem), "--motion", str(path), "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert "IK fit of the c3d file" in result.output
    rows = list(csv.DictReader((out / "timeline.csv").open()))
    names = cp.load(SEATED).body.dof_names
    got = np.radians([[float(r[f"{n}_deg"]) for n in names] for r in rows])
    np.testing.assert_allclose(got, q, atol=1e-6)
    assert max(float(r["marker_residual_elbow_r_m"]) for r in rows) < 1e-4
    assert [r["held_part"] for r in rows] == ["1", "1", "0", "0"]
    assert "fit to the markers (mm)" not in (out / "report.html").read_text()  # it has a task


def test_calibration_places_markers_that_sit_off_their_landmarks(seated: cp.Problem) -> None:
    """Each marker 2-4 cm off its landmark, fixed on the landmark's segment (skin markers
    are not joint centres), the subject in posture_deg for the first frame: calibrated on
    that frame, every angle of the moving frames within 6° (what is left is the calibration
    frame's own fit of the lab onto landmarks its markers are off: 1.3° with 1 cm offsets,
    0 with none); not calibrated, tens of degrees off."""
    body = seated.body
    q = np.vstack([seated.posture, _motion(seated, MOVED_DEG)])
    rng = np.random.default_rng(3)
    offsets = {n: rng.uniform(0.02, 0.04, 3) * rng.choice([-1, 1], 3) for n in LANDMARKS}
    turn = ca.Function("turn", [body.q], [body.rotation(body.landmarks[n].dof) for n in LANDMARKS])
    at = ca.Function("at", [body.q], [ca.horzcat(*[body.landmark(n) for n in LANDMARKS]).T])
    world = np.array(
        [
            np.asarray(at(qk))
            + np.array(
                [np.asarray(r) @ offsets[n] for r, n in zip(turn(qk), LANDMARKS, strict=True)]
            )
            for qk in q
        ]
    )
    lab = (world - T_LAB) @ R_LAB
    mapping = {n: [n.upper()] for n in LANDMARKS}
    markers = Markers(
        Path("off.c3d"), np.arange(len(q)) / RATE_HZ, tuple(n.upper() for n in LANDMARKS), lab
    )
    args = (markers, body, mapping, seated.posture, "lexicographic")
    up = R_LAB.T @ (0.0, 0.0, 1.0)  # the body's vertical in the lab
    recording, _ = markers_to_recording(*args, calibration_s=(0.0, 0.0), lab_up=up)
    assert np.degrees(np.abs(recording.q - q).max()) < 6.0
    assert any("calibrated on 0-0 s" in n for n in recording.notes)
    uncalibrated, _ = markers_to_recording(*args)
    assert np.degrees(np.abs(uncalibrated.q - q).max()) > 20.0
    with pytest.raises(ProblemError, match="calibrate_s"):
        markers_to_recording(*args, problem=Path("p.toml"), calibration_s=(5.0, 6.0), lab_up=up)


def test_the_report_of_a_recording_without_tasks_shows_the_marker_fit(
    recorded: tuple, tmp_path: Path
) -> None:
    """No task, so no task residual: the page's third panel is each point's fit [mm]."""
    import tomllib

    _, _, mapping, path = recorded
    data = tomllib.loads(Path(SEATED).read_text())
    del data["tasks"]
    data["motion"] = {"markers": mapping}
    run = cp.evaluate(cp.from_dict(data, "no_tasks.toml"), path)
    run.write(tmp_path / "out")
    page = (tmp_path / "out" / "report.html").read_text()
    assert "fit to the markers (mm)" in page and "task residuals" not in page


def test_segments_are_scaled_to_the_subject_from_the_static_window(
    seated: cp.Problem, tmp_path: Path
) -> None:
    """A subject with longer upper arms (0.31 m) and forearms (0.28 m) than the body: the
    static first frame gives both lengths back to 1e-5 m (the file's float32 in mm), the
    body built with them fits every frame, every angle back to 1e-5 rad (but the forearms'
    turn, which these markers do not show) and evaluate runs on it; read without
    scaling, the same markers are centimetres off. A segment the body has not, no static
    window, or markers on other landmarks (a length 0.1× the body's) are one-line errors."""
    subject = cp.load(
        SEATED, {"body.segments.upper_arm.length_m": 0.31, "body.segments.forearm.length_m": 0.28}
    )
    q = np.vstack([seated.posture, _motion(seated, MOVED_DEG)])
    turn = rotation_rpy(0.0, 0.0, 2.5)  # the lab turned about its vertical z
    at = ca.Function(
        "at", [subject.body.q], [ca.horzcat(*[subject.body.landmark(n) for n in LANDMARKS]).T]
    )
    lab = np.array([(np.asarray(at(qk)) - T_LAB) @ turn for qk in q])
    path = _write_c3d(tmp_path / "subject.c3d", [n.upper() for n in LANDMARKS], lab)
    mapping = {n: [n.upper()] for n in LANDMARKS}
    keys = {"motion.markers": mapping, "motion.calibrate_s": [0.0, 0.0]}
    scaling = cp.load(SEATED, {**keys, "motion.scale_segments": ["upper_arm", "forearm"]})
    recording = cp.read_motion(scaling, path, solver="nullspace")
    assert recording.segment_lengths_m == pytest.approx(
        {"upper_arm": 0.31, "forearm": 0.28}, abs=1e-5
    )
    assert any("forearm 0.266 → 0.280 m" in n for n in recording.notes)
    # a forearm's turn is not seen: its wrist, grip and knuckles lie on its axis
    seen = [i for i, d in enumerate(seated.body.dof_names) if "pronation" not in d]
    np.testing.assert_allclose(recording.q[:, seen], q[:, seen], atol=1e-5)
    assert max(r.max() for r in recording.residuals.values()) < 1e-5
    run = cp.evaluate(scaling, recording)
    assert run.result.problem.overrides["body.segments.forearm.length_m"] == pytest.approx(
        0.28, abs=1e-5
    )
    plain = cp.read_motion(cp.load(SEATED, keys), path, solver="nullspace")
    assert max(r.max() for r in plain.residuals.values()) > 0.01
    for sets, match in (
        ({**keys, "motion.scale_segments": ["thigh"]}, "thigh"),
        ({"motion.markers": mapping, "motion.scale_segments": ["forearm"]}, "calibrate_s"),
        (
            {
                **keys,
                "motion.markers": {**mapping, "wrist_r": ["ELBOW_R"]},
                "motion.scale_segments": ["forearm"],
            },
            "the body's",
        ),
    ):
        with pytest.raises(ProblemError, match=match):
            cp.read_motion(cp.load(SEATED, sets), path, solver="nullspace")


def _unseen(labels: list[str], points: np.ndarray) -> None:
    points[:3, labels.index("STYLr")] = np.nan


def _twice(labels: list[str], points: np.ndarray) -> None:
    labels[labels.index("STYLu")] = "STYLr"


def _infinite(labels: list[str], points: np.ndarray) -> None:
    points[0, labels.index("ASISr"), 11] = np.inf


def _far(labels: list[str], points: np.ndarray) -> None:
    points[2, labels.index("T1"), 4] = 2e5  # 200 m in mm


def _renamed(labels: list[str], points: np.ndarray) -> None:
    labels[labels.index("STYLr")] = "STYL_R"


@pytest.mark.parametrize(
    ("change", "key", "said"),
    [
        (_renamed, "motion.markers.wrist_r = 'STYLr'", "a marker label of {c3d} (did you mean"),
        (_twice, "motion.markers.wrist_r = 'STYLr'", "found once in {c3d} (it is there 2 times)"),
        (_unseen, "motion.scale_segments = 'forearm'", "wrist_r are seen in {c3d}"),
        (_infinite, "{c3d}: ASISr (frame 12, x in m) = inf", "within 100 m of the lab's origin"),
        (_far, "{c3d}: T1 (frame 5, z in m) = 200.0", "within 100 m of the lab's origin"),
    ],
)
def test_a_marker_missing_twice_unseen_or_infinite_is_one_line_naming_the_file(
    change: Callable[[list[str], np.ndarray], None], key: str, said: str, tmp_path: Path
) -> None:
    """The shipped C3D file with a marker renamed, named as another, never seen, or with an
    infinite or far coordinate (internal errors before: ValueError, LinAlgError, TypeError)."""
    c3d = short_c3d(tmp_path / "box.c3d", change)
    invoked = invoke(evaluate(BOX, c3d, tmp_path / "out"))
    assert invoked.exit_code == 2 and not problems(invoked, c3d), invoked
    assert key.format(c3d=c3d) in invoked.stderr and said.format(c3d=c3d) in invoked.stderr


def test_a_label_not_in_the_file_is_refused_with_the_labels_there_are(tmp_path: Path) -> None:
    """A mapped label the file does not have (met first when the segments are scaled: an
    internal error before) names the file's labels when none is close; a label twice in a
    list, or hundreds of them, is refused by the problem file's schema."""
    c3d = short_c3d(tmp_path / "box.c3d")
    wrist = "motion.markers.wrist_r=['STYLr', 'ZZZ']"
    invoked = invoke([*evaluate(BOX, c3d, tmp_path / "out"), "--set", wrist])
    assert invoked.exit_code == 2 and not problems(invoked, c3d), invoked
    labels = read_c3d(c3d).labels
    assert f"motion.markers.wrist_r = 'ZZZ': expected a marker label of {c3d}" in invoked.stderr
    assert f"(its {len(labels)} labels: ACRO_tip, ARMl, " in invoked.stderr
    many = {"motion.markers.pelvis": ["ASISr", "ASISl", "PSISr", "PSISl"] * 100}
    message = _error(cp.load, BOX, many)
    assert message.endswith(
        "motion.markers: expected pelvis: each label once ('ASISr' is there 100 times)"
    )


def test_a_file_cut_short_is_refused_with_the_frames_its_header_declares(tmp_path: Path) -> None:
    """ezc3d reads a C3D file cut short without a word (the frames it holds); the header says
    how many there were."""
    c3d = short_c3d(tmp_path / "box.c3d")
    data = c3d.read_bytes()
    cut = tmp_path / "cut.c3d"
    cut.write_bytes(data[: len(data) - 3000])
    message = _error(read_c3d, cut)
    held = ezc3d.c3d(str(cut))["data"]["points"].shape[2]
    expected = "expected the 30 frames its header declares: the file is cut short"
    assert message == f"{cut}: frames = {held}: {expected}"
    assert read_c3d(c3d).time.size == 30
