"""The 3-D bodies ``upper_body`` and ``standing`` (body/human.py, body/support.py).

- Gravity torques reproduced by pinocchio from ``describe --json`` alone; for ``standing``
  the floor's reaction on the carried (left) foot is rebuilt in the test from pinocchio's
  centre of mass and frame Jacobians and the feet the JSON prints, by the rule of
  body/support.py's docstring.
- Segment masses against de Leva (1996) Table 4, joint centres at the zero posture against
  the sources' regressions, every number typed here from the papers (never read back from
  the package's data files).
- The sign conventions of human.py's docstring, and the support polygon of the feet.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import PROBLEMS
from pinocchio_bodies import pinocchio_model

from casadi_posture import api
from casadi_posture.biomech.torques import TorqueModel
from casadi_posture.body import human, support
from casadi_posture.body.anthropometry import segment_inertia
from casadi_posture.cli import main
from casadi_posture.problem import Problem

G = 9.81

# Reference bodies of de Leva (1996): stature [m], body mass [kg].
REFERENCE = {"male": (1.741, 73.0), "female": (1.735, 61.9)}

# de Leva 1996, Table 4: mass fractions of body mass (head with neck; trunk = upper + middle
# + lower parts) and the lengths [m] of the reference samples.
DE_LEVA_MASS = {
    "male": {
        "head_neck": 0.0694,
        "trunk": 0.4346,
        "upper_arm": 0.0271,
        "forearm": 0.0162,
        "hand": 0.0061,
        "thigh": 0.1416,
        "shank": 0.0433,
        "foot": 0.0137,
    },
    "female": {
        "head_neck": 0.0668,
        "trunk": 0.4257,
        "upper_arm": 0.0255,
        "forearm": 0.0138,
        "hand": 0.0056,
        "thigh": 0.1478,
        "shank": 0.0481,
        "foot": 0.0129,
    },
}
# de Leva 1996, Table 4, thigh (hip to knee centre) and shank (knee centre to lateral
# malleolus): centre of mass from the proximal end, radii of gyration (sagittal, transverse,
# longitudinal), as fractions of the segment's length.
DE_LEVA_LEG = {
    "male": {"thigh": (0.4095, (0.329, 0.329, 0.149)), "shank": (0.4459, (0.255, 0.249, 0.103))},
    "female": {"thigh": (0.3612, (0.369, 0.364, 0.162)), "shank": (0.4416, (0.271, 0.267, 0.093))},
}
# de Leva 1996, Table 4, upper arm (shoulder to elbow centre) and forearm (elbow to wrist
# centre), as DE_LEVA_LEG.
DE_LEVA_ARM = {
    "male": {
        "upper_arm": (0.5772, (0.285, 0.269, 0.158)),
        "forearm": (0.4574, (0.276, 0.265, 0.121)),
    },
    "female": {
        "upper_arm": (0.5754, (0.278, 0.260, 0.148)),
        "forearm": (0.4559, (0.261, 0.257, 0.094)),
    },
}
DE_LEVA_FOOT = {"male": (0.2581, 0.4415), "female": (0.2283, 0.4014)}  # length, CoM from heel

# ANSUR II (2012) means [m]: stature, acromial height, biacromial breadth, lateral malleolus
# height, foot length, foot breadth, heel breadth, ball-of-foot length, trochanterion height,
# knee height (mid-patella), iliocristale height, acromion–radiale and radiale–stylion lengths,
# and wrist height (floor to stylion, arms hanging), which the model does not use.
ANSUR = {
    "male": {
        "stature": 1.756,
        "trochanterion": 0.901,
        "knee_mid_patella": 0.488,
        "iliocristale": 1.062,
        "acromial": 1.441,
        "biacromial": 0.4157,
        "malleolus": 0.0729,
        "foot_length": 0.2712,
        "foot_breadth": 0.1019,
        "heel_breadth": 0.0725,
        "ball_length": 0.2009,
        "acromion_radiale": 0.3352,
        "radiale_stylion": 0.2679,
        "wrist": 0.8475,
    },
    "female": {
        "stature": 1.629,
        "trochanterion": 0.845,
        "knee_mid_patella": 0.449,
        "iliocristale": 0.996,
        "acromial": 1.335,
        "biacromial": 0.3653,
        "malleolus": 0.0627,
        "foot_length": 0.2463,
        "foot_breadth": 0.0927,
        "heel_breadth": 0.0672,
        "ball_length": 0.1821,
        "acromion_radiale": 0.3112,
        "radiale_stylion": 0.2413,
        "wrist": 0.7942,
    },
}
RAB_GH_BELOW_ACROMION = 0.17  # Rab 2002, × biacromial breadth
# Reed 1999 (fractions of pelvis width PW) with Dumas 2007's PW at de Leva's stature:
# PW, hip lateral, hip down, hip back, L5/S1 up, L5/S1 back.
REED = {
    "male": (0.224, 0.361, 0.278, 0.208, 0.126, 0.264),
    "female": (0.238, 0.372, 0.270, 0.197, 0.172, 0.289),
}
# The model's own choices for the foot (human.py, "estimates"): the heel behind the ankle by
# 0.2 foot length, the toes' outline half the foot breadth.
HEEL_BEHIND_ANKLE, TOE_WIDTH = 0.2, 0.5

WRIST_TARGET = "[0.3, -0.2, 1.0]"


def _text(
    model: str,
    sex: str = "male",
    stature: float | None = None,
    mass: float | None = None,
    loads: tuple[dict[str, Any], ...] = (),
) -> str:
    """A minimal problem: ``model`` scaled to the body, one position task on ``wrist_r``."""
    stature, mass = (stature, mass) if stature is not None else REFERENCE[sex]
    lines = [
        'title = "3-D body test"',
        "[body]",
        f'model = "{model}"',
        f'sex = "{sex}"',
        f"stature_m = {stature!r}",
        f"mass_kg = {mass!r}",
    ]
    for load in loads:
        lines += ["[[loads]]", *(f"{k} = {json.dumps(v)}" for k, v in load.items())]
    lines += [
        "[[tasks]]",
        'name = "reach"',
        'kind = "position"',
        'effector = "wrist_r"',
        "priority = 1",
        f"target_m = {WRIST_TARGET}",
    ]
    return "\n".join(lines) + "\n"


def _problem(model: str, sex: str = "male", stature: float | None = None, **kw: Any) -> Problem:
    return api.loads(_text(model, sex, stature, **kw), name=f"<{model} {sex}>")


def _landmarks(problem: Problem, q: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Every landmark's world position [m] at ``q`` (default zero) by the compiled kinematics."""
    body = problem.body
    names = list(body.landmarks)
    f = ca.Function("landmarks", [body.q], [ca.horzcat(*[body.landmark(n) for n in names])])
    x = np.asarray(f(np.zeros(body.n) if q is None else q))
    return {n: x[:, i] for i, n in enumerate(names)}


def _q(problem: Problem, **degrees: float) -> np.ndarray:
    q = np.zeros(problem.body.n)
    for name, angle in degrees.items():
        q[problem.body.index[name]] = np.radians(angle)
    return q


# --- 1. Gravity torques against pinocchio ----------------------------------------------

HELD = {"name": "weight", "at": "wrist_r", "mass_kg": 2.5}
PUSH = {
    "name": "push",
    "at": "wrist_r",
    "mass_kg": 2.5,
    "force_N": [15.0, -8.0, 5.0],
    "moment_Nm": [1.0, -2.0, 0.5],
}


class Pinocchio:
    """A described body in pinocchio with frames at the loads' points and the carried sole's
    centre, and the external torque the package should print, computed from it alone."""

    def __init__(self, pin: Any, described: dict[str, Any]) -> None:
        self.pin, self.described = pin, described
        self.model, self.dofs = pinocchio_model(described)
        origin = {d["name"]: np.array(d["origin_m"]) for d in described["dofs"]}

        def frame(name: str, dof: str, point: np.ndarray) -> int:
            placement = pin.SE3(np.eye(3), np.asarray(point) - origin[dof])
            joint = self.model.getJointId(dof)
            return self.model.addFrame(pin.Frame(name, joint, placement, pin.FrameType.OP_FRAME))

        self.loads = [
            (frame(f"load_{ld['name']}", ld["dof"], ld["point_m"]), ld) for ld in described["loads"]
        ]
        # Masses fixed to the world take no torque and are not in pinocchio's model.
        self.fixed = [
            (s["mass_kg"], np.array(s["com_m"])) for s in described["segments"] if "dof" not in s
        ]
        feet = described.get("feet", [])
        self.root = next((f for f in feet if "dof" not in f), None)
        self.carried = next((f for f in feet if "dof" in f), None)
        if self.carried is not None:
            centre = np.mean(np.array(self.carried["outline_m"]), axis=0)
            self.sole = frame("carried_sole", self.carried["dof"], centre)
        self.data = self.model.createData()

    def weight(self, q: np.ndarray) -> tuple[float, np.ndarray]:
        """Total mass [kg] (segments and held loads) and its centre of mass [m] at ``q``."""
        com = self.pin.centerOfMass(self.model, self.data, q)
        mass = self.data.mass[0]
        for m, c in self.fixed:
            com, mass = (mass * com + m * c) / (mass + m), mass + m
        return mass, com

    def jacobian(self, frame: int, q: np.ndarray) -> np.ndarray:
        """6×n: linear velocity of the frame's origin, then angular velocity (world axes)."""
        pin = self.pin
        pin.computeJointJacobians(self.model, self.data, q)
        pin.updateFramePlacements(self.model, self.data)
        return pin.getFrameJacobian(self.model, self.data, frame, pin.LOCAL_WORLD_ALIGNED)

    def reaction(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """The floor's reaction on the carried foot by support.py's rule: its force [N], the
        sole centre [m], the arm [m] from that centre to the force's point on the floor and
        its couple about the vertical [N·m] (the share s of the whole reaction)."""
        gravity = np.array([0.0, 0.0, -self.described["gravity_m_s2"]])
        mass, com = self.weight(q)
        total = mass * gravity
        moment = np.cross(com, mass * gravity)
        for frame, load in self.loads:
            self.pin.framesForwardKinematics(self.model, self.data, q)
            point = self.data.oMf[frame].translation
            total = total + np.array(load["force_N"])
            moment = moment + np.cross(point, load["force_N"]) + np.array(load["moment_Nm"])
        # Centre of pressure: the moment about the vertical through it has no horizontal part.
        pressure = np.array([-moment[1], moment[0]]) / total[2]
        self.pin.framesForwardKinematics(self.model, self.data, q)
        centre = self.data.oMf[self.sole].translation.copy()
        root = np.mean(np.array(self.root["outline_m"]), axis=0)[:2]
        line = centre[:2] - root
        share = np.dot(pressure - root, line) / np.dot(line, line)
        offset = pressure - (root + share * line)
        # The moment about the vertical through the pressure point, shared by the same s.
        twist = moment[2] - (pressure[0] * total[1] - pressure[1] * total[0])
        force = -share * total
        return force, centre, np.array([offset[0], offset[1], -centre[2]]), -share * twist

    def external(self, q: np.ndarray) -> np.ndarray:
        """τe [N·m] = -g(q) + pushes + the floor's reaction on the carried foot."""
        pin = self.pin
        tau = -pin.computeGeneralizedGravity(self.model, self.data, q)
        for frame, load in self.loads:
            j = self.jacobian(frame, q)
            tau += j[:3].T @ np.array(load["force_N"]) + j[3:].T @ np.array(load["moment_Nm"])
        return tau + self.floor(q)

    def floor(self, q: np.ndarray) -> np.ndarray:
        """The torque [N·m] of the floor's reaction on the carried foot, Jᵀ F + J_ωᵀ (arm × F)
        (zero for a body without feet)."""
        if self.carried is None:
            return np.zeros(self.model.nv)
        force, _, arm, couple = self.reaction(q)
        j = self.jacobian(self.sole, q)
        return j[:3].T @ force + j[3:].T @ (np.cross(arm, force) + np.array([0.0, 0.0, couple]))


@pytest.fixture(scope="module")
def pin() -> Any:
    return pytest.importorskip("pinocchio")


def _described(path: Path) -> dict[str, Any]:
    result = CliRunner().invoke(main, ["describe", str(path), "--json"])
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def _random_postures(described: dict[str, Any], count: int, seed: int) -> np.ndarray:
    ranges = np.radians([d["range_deg"] for d in described["dofs"]])
    rng = np.random.default_rng(seed)
    return rng.uniform(ranges[:, 0], ranges[:, 1], size=(count, len(ranges)))


CASES = {
    "upper_body-male-no_load": ("upper_body", "male", ()),
    "upper_body-male-held": ("upper_body", "male", (HELD,)),
    "upper_body-female-push": ("upper_body", "female", (PUSH,)),
    "standing-male-no_load": ("standing", "male", ()),
    "standing-female-held": ("standing", "female", (HELD,)),
    "standing-male-push": ("standing", "male", (PUSH,)),
    "standing_wall_horizontal": (None, None, None),
}


@pytest.mark.parametrize("case", list(CASES))
def test_external_torques_match_pinocchio(case: str, pin: Any, tmp_path: Path) -> None:
    """τe of ``Problem.torque_model()`` equals pinocchio's -g(q) plus the pushes and, standing,
    the floor's reaction on the left foot, at 6 random postures in the ranges, to 1e-9 N·m."""
    model, sex, loads = CASES[case]
    if model is None:
        path = PROBLEMS / "standing_wall_horizontal.toml"
    else:
        path = tmp_path / f"{case}.toml"
        path.write_text(_text(model, sex, loads=loads))
    described = _described(path)
    problem = api.load(path)
    assert [ld["mass_kg"] for ld in described["loads"]] == [ld.mass for ld in problem.loads]
    standing = described["model"] == "standing"
    # The JSON carries both feet: the root (right) one fixed, the left one on a DOF.
    assert len(described["feet"]) == (2 if standing else 0)
    reference = Pinocchio(pin, described)
    torques = problem.torque_model()
    reaction = 0.0
    for q in _random_postures(described, 6, seed=len(case)):
        expected = reference.external(q)
        got = torques.evaluate(q).external
        assert np.max(np.abs(got - expected)) < 1e-9, (q, got - expected)
        reaction = max(reaction, np.max(np.abs(reference.floor(q))))
    # Standing, the floor's reaction is not negligible: leaving it out misses by N·m.
    assert reaction > 1.0 if standing else reaction == 0.0


def _symmetric_posture(problem: Problem, rng: np.random.Generator) -> np.ndarray:
    """Equal sagittal angles on both legs, mirrored arms, lumbar flexion only."""
    angles: dict[str, float] = {"lumbar_flexion": float(rng.uniform(-10, 30))}
    legs = {"hip_flexion": (-10, 40), "knee_flexion": (0, 60), "ankle_flexion": (-15, 15)}
    arms = {
        "shoulder_flexion": (0, 90),
        "shoulder_abduction": (0, 60),
        "shoulder_rotation": (-30, 30),
        "elbow_flexion": (10, 120),
        "forearm_pronation": (-40, 40),
        "wrist_flexion": (-30, 30),
        "wrist_deviation": (-10, 10),
    }
    for kind, (lo, hi) in {**legs, **arms}.items():
        angle = float(rng.uniform(lo, hi))
        angles[f"{kind}_r"] = angles[f"{kind}_l"] = angle
    return _q(problem, **angles)


def _carried_reaction(
    reference: Pinocchio, torques: TorqueModel, q: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The floor's force on the carried foot [N] and its point on the floor [m], read back from
    the package's torques: τe + g(q) - pushes = Jᵀ w, w the wrench at the carried sole's centre."""
    tau = torques.evaluate(q).external
    pin = reference.pin
    tau_pushes = -pin.computeGeneralizedGravity(reference.model, reference.data, q)
    for frame, load in reference.loads:
        j = reference.jacobian(frame, q)
        tau_pushes += j[:3].T @ np.array(load["force_N"]) + j[3:].T @ np.array(load["moment_Nm"])
    j = reference.jacobian(reference.sole, q)
    wrench, *_ = np.linalg.lstsq(j.T, tau - tau_pushes, rcond=None)
    assert np.max(np.abs(j.T @ wrench - (tau - tau_pushes))) < 1e-9
    force, moment = wrench[:3], wrench[3:]
    centre = reference.data.oMf[reference.sole].translation
    # The force acts on the floor (arm z = -centre z): solve arm × force = moment for x, y.
    down = -centre[2]
    arm = np.array(
        [(down * force[0] - moment[1]) / force[2], (moment[0] + down * force[1]) / force[2], down]
    )
    point = centre + arm
    return force, point


def test_symmetric_stance_shares_the_weight_equally(pin: Any, tmp_path: Path) -> None:
    """Mirror-symmetric posture and loads: each leg DOF carries the same torque as its mirror
    (anatomical signs), the feet take half the weight each and the vertical reactions add up
    to the body weight plus the loads."""
    loads = (HELD, {**HELD, "name": "weight_l", "at": "wrist_l"})
    path = tmp_path / "symmetric.toml"
    path.write_text(_text("standing", loads=loads))
    problem = api.load(path)
    reference = Pinocchio(pin, _described(path))
    torques = problem.torque_model()
    dofs = problem.body.dof_names
    rng = np.random.default_rng(5)
    for _ in range(5):
        q = _symmetric_posture(problem, rng)
        pin.framesForwardKinematics(reference.model, reference.data, q)
        feet = np.array(reference.carried["outline_m"])
        tau = torques.evaluate(q).external
        for kind in ("hip", "knee", "ankle"):
            # Sagittal: loaded, and alike (not zero on both sides by accident).
            right, left = tau[dofs.index(f"{kind}_flexion_r")], tau[dofs.index(f"{kind}_flexion_l")]
            assert abs(right - left) < 1e-9 and abs(right) > 0.1, (kind, right, left)
        for kind in ("hip_abduction", "hip_rotation", "ankle_inversion"):
            # Each foot straight below its hip takes half the weight: no frontal torque.
            right, left = tau[dofs.index(f"{kind}_r")], tau[dofs.index(f"{kind}_l")]
            assert abs(right) < 1e-9 and abs(left) < 1e-9, (kind, right, left)
        for name in ("lumbar_bending", "lumbar_rotation"):
            assert abs(tau[dofs.index(name)]) < 1e-9
        mass, _ = reference.weight(q)
        weight = mass * G
        assert mass == pytest.approx(73.0 + 5.0, abs=1e-9)
        force, point = _carried_reaction(reference, torques, q)
        # Half the weight of body and loads on the carried foot, so the root foot's remainder
        # is the other half: the two add up to the weight of the body plus the loads.
        assert force[2] == pytest.approx(weight / 2, abs=1e-9)
        # The left foot is the mirror of the right one, still flat on the floor.
        sole = reference.data.oMf[reference.sole].translation
        assert abs(sole[2] - np.mean(feet[:, 2])) < 1e-12
        assert abs(sole[1] + np.mean(np.array(reference.root["outline_m"])[:, 1])) < 1e-12
        assert abs(point[1] - sole[1]) < 1e-9


def test_a_symmetric_push_is_shared_equally(pin: Any, tmp_path: Path) -> None:
    """Both hands push forward with 40 N in a mirror-symmetric stance: each foot takes half
    the horizontal reaction (-40 N) as it takes half the weight, so each leg DOF carries the
    torque of its mirror (the horizontal force once went all to the root foot: hip torques
    of -13.8 and +60.4 N·m)."""
    push = {"name": "push_r", "at": "wrist_r", "mass_kg": 0.0, "force_N": [40.0, 0.0, 0.0]}
    path = tmp_path / "push.toml"
    path.write_text(_text("standing", loads=(push, {**push, "name": "push_l", "at": "wrist_l"})))
    problem = api.load(path)
    reference = Pinocchio(pin, _described(path))
    torques = problem.torque_model()
    dofs = problem.body.dof_names
    rng = np.random.default_rng(11)
    for _ in range(4):
        q = _symmetric_posture(problem, rng)
        tau = torques.evaluate(q).external
        for kind in ("hip_flexion", "knee_flexion", "ankle_flexion", "hip_abduction"):
            right, left = tau[dofs.index(f"{kind}_r")], tau[dofs.index(f"{kind}_l")]
            assert abs(right - left) < 1e-9, (kind, right, left)
        for name in ("lumbar_bending", "lumbar_rotation"):
            assert abs(tau[dofs.index(name)]) < 1e-9
        force, _ = _carried_reaction(reference, torques, q)
        assert force == pytest.approx([-40.0, 0.0, reference.weight(q)[0] * G / 2], abs=1e-9)


def test_reactions_balance_weight_and_loads(pin: Any, tmp_path: Path) -> None:
    """At asymmetric postures the carried foot's reaction read back from the package's torques
    plus the root foot's remainder (the rule's (1 - s)·W at its sole centre + d) balance the
    weight, the held load and a push: the vertical forces add up to the weight plus the
    loads less the push's lift, and the two act at the centre of pressure."""
    path = tmp_path / "push.toml"
    path.write_text(_text("standing", loads=(PUSH,)))
    problem = api.load(path)
    reference = Pinocchio(pin, _described(path))
    torques = problem.torque_model()
    root = np.mean(np.array(reference.root["outline_m"]), axis=0)
    rng = np.random.default_rng(9)
    for _ in range(5):
        angles = {
            "hip_flexion_l": rng.uniform(-20, 30),
            "knee_flexion_l": rng.uniform(0, 40),
            "lumbar_flexion": rng.uniform(0, 40),
            "lumbar_rotation": rng.uniform(-20, 20),
            "shoulder_flexion_r": rng.uniform(0, 90),
            "hip_rotation_r": rng.uniform(-20, 20),
        }
        q = _q(problem, **angles)
        mass, com = reference.weight(q)
        force, point = _carried_reaction(reference, torques, q)
        # Weight and push on the body; the push's point and its moment move the pressure.
        pin.framesForwardKinematics(reference.model, reference.data, q)
        wrist = reference.data.oMf[reference.loads[0][0]].translation
        push, push_moment = np.array(PUSH["force_N"]), np.array(PUSH["moment_Nm"])
        vertical = mass * G - push[2]
        moment = np.cross(com, [0.0, 0.0, -mass * G]) + np.cross(wrist, push) + push_moment
        pressure = np.array([moment[1], -moment[0]]) / vertical
        # The floor's total (carried + root) carries the vertical load at the pressure point.
        root_force = vertical - force[2]
        offset = point[:2] - reference.data.oMf[reference.sole].translation[:2]
        root_point = root[:2] + offset
        assert force[2] + root_force == pytest.approx(vertical, abs=1e-9)
        both = (force[2] * point[:2] + root_force * root_point) / vertical
        assert np.max(np.abs(both - pressure)) < 1e-9
        assert 0.0 < force[2] < vertical  # the pressure lies between the feet here


# --- 2. Masses ----------------------------------------------------------------------------

SIZES = [
    ("male", 1.741, 73.0),
    ("female", 1.735, 61.9),
    ("female", 1.60, 55.0),
    ("male", 1.90, 95.0),
]


def _de_leva_total(sex: str, legs: bool) -> float:
    """Sum of de Leva's mass fractions over the body's segments, both sides."""
    f = DE_LEVA_MASS[sex]
    total = f["head_neck"] + f["trunk"] + 2 * (f["upper_arm"] + f["forearm"] + f["hand"])
    return total + (2 * (f["thigh"] + f["shank"] + f["foot"]) if legs else 0.0)


@pytest.mark.parametrize("sex, stature, mass", SIZES, ids=lambda v: str(v))
def test_segment_masses(sex: str, stature: float, mass: float) -> None:
    """``standing``'s segments weigh the body mass and ``upper_body``'s the body less two
    thighs, shanks and feet, as far as de Leva's fractions allow: the male ones add up to
    1.0000, the female ones to 0.9999 (head 6.68 + trunk 42.57 + 2 × 25.37 %, the table's
    rounding), so a female body's segments weigh 0.01 % less than its mass (6.19 g at
    61.9 kg). Should the model renormalise them, the female expectation changes here."""
    f = DE_LEVA_MASS[sex]
    whole = _de_leva_total(sex, legs=True)
    assert whole == pytest.approx({"male": 1.0, "female": 0.9999}[sex], abs=1e-12)
    standing = _problem("standing", sex, stature, mass=mass).body
    upper = _problem("upper_body", sex, stature, mass=mass).body
    assert standing.total_mass == pytest.approx(whole * mass, abs=1e-9)
    legs = 2 * (f["thigh"] + f["shank"] + f["foot"]) * mass
    assert upper.total_mass == pytest.approx(whole * mass - legs, abs=1e-9)
    if sex == "male":
        assert standing.total_mass == pytest.approx(mass, abs=1e-9)
    segment = {s.name: s.mass for s in standing.segments}
    for side in ("r", "l"):
        for name in ("thigh", "shank", "foot", "upper_arm", "forearm", "hand"):
            assert segment[f"{name}_{side}"] == pytest.approx(f[name] * mass, abs=1e-9)
    trunk = sum(segment[p] for p in ("upper_trunk", "middle_trunk", "lower_trunk"))
    assert trunk == pytest.approx(f["trunk"] * mass, abs=1e-9)
    assert segment["head_neck"] == pytest.approx(f["head_neck"] * mass, abs=1e-9)


# --- 3. Joint centres ------------------------------------------------------------------------


def _expected_centres(sex: str, stature: float) -> dict[str, np.ndarray]:
    """Joint centres [m] at the zero posture by the sources' regressions (see the module)."""
    a = ANSUR[sex]
    ansur = stature / a["stature"]
    de_leva = stature / REFERENCE[sex][0]
    pw, hip_lateral, hip_down, hip_back, l5s1_up, l5s1_back = REED[sex]
    pw *= de_leva
    shoulder_z = (a["acromial"] - RAB_GH_BELOW_ACROMION * a["biacromial"]) * ansur
    shoulder_y = a["biacromial"] / 2 * ansur
    hip_y = hip_lateral * pw
    # The hip centre at the trochanterion, the knee's at mid-patella, the ankle's at the
    # lateral malleolus.
    ankle_z = a["malleolus"] * ansur
    knee_z = a["knee_mid_patella"] * ansur
    hip_z = a["trochanterion"] * ansur
    # The arm hangs straight: the elbow centre at radiale, the wrist's at stylion.
    elbow_z = (a["acromial"] - a["acromion_radiale"]) * ansur
    wrist_z = elbow_z - a["radiale_stylion"] * ansur
    out = {
        "shoulder_r": (0.0, -shoulder_y, shoulder_z),
        "elbow_r": (0.0, -shoulder_y, elbow_z),
        "elbow_l": (0.0, shoulder_y, elbow_z),
        "wrist_r": (0.0, -shoulder_y, wrist_z),
        "wrist_l": (0.0, shoulder_y, wrist_z),
        "shoulder_l": (0.0, shoulder_y, shoulder_z),
        "hip_r": (0.0, -hip_y, hip_z),
        "hip_l": (0.0, hip_y, hip_z),
        "mid_hip": (0.0, 0.0, hip_z),
        "l5s1": (-(l5s1_back - hip_back) * pw, 0.0, hip_z + (l5s1_up + hip_down) * pw),
        "knee_r": (0.0, -hip_y, knee_z),
        "knee_l": (0.0, hip_y, knee_z),
        "ankle_r": (0.0, -hip_y, ankle_z),
        "ankle_l": (0.0, hip_y, ankle_z),
    }
    return {k: np.array(v) for k, v in out.items()}


@pytest.mark.parametrize("model", ["standing", "upper_body"])
@pytest.mark.parametrize("sex", ["male", "female"])
def test_joint_centres_at_zero_posture(model: str, sex: str) -> None:
    stature = REFERENCE[sex][0]
    expected = _expected_centres(sex, stature)
    got = _landmarks(_problem(model, sex))
    # upper_body stands its pelvis at the standing hip height by default; it has no legs.
    names = [n for n in expected if model == "standing" or not n.startswith(("knee", "ankle"))]
    assert set(names) <= set(got)
    for name in names:
        assert np.max(np.abs(got[name] - expected[name])) < 1e-6, (name, got[name])


@pytest.mark.parametrize("sex", ["male", "female"])
def test_leg_centres_at_ansur_landmarks_at_the_ansur_mean_stature(sex: str) -> None:
    """At ANSUR II's mean stature the hip centres stand at the mean trochanterion height and
    the knees' at the mean knee height (mid-patella); a woman's L5/S1 lies less than 60 mm
    below her mean iliocristale height (the iliac crest's top is about at L4/L5)."""
    a = ANSUR[sex]
    got = _landmarks(_problem("standing", sex, a["stature"], mass=70.0))
    for side in ("r", "l"):
        assert got[f"hip_{side}"][Z] == pytest.approx(a["trochanterion"], abs=1e-9)
        assert got[f"knee_{side}"][Z] == pytest.approx(a["knee_mid_patella"], abs=1e-9)
        assert got[f"ankle_{side}"][Z] == pytest.approx(a["malleolus"], abs=1e-9)
    if sex == "female":
        assert 0.0 < a["iliocristale"] - got["l5s1"][Z] < 0.060


@pytest.mark.parametrize("sex", ["male", "female"])
def test_arm_centres_against_ansur_at_the_ansur_mean_stature(sex: str) -> None:
    """At ANSUR II's mean stature the elbow centres stand at the mean radiale height, the
    forearm is the mean radiale–stylion length, and the wrist centres of the straight hanging
    arm lie within 15 mm below the survey's mean wrist height, measured on relaxed arms that
    hang a little bent and away from the body (a measurement the model does not use)."""
    a = ANSUR[sex]
    got = _landmarks(_problem("standing", sex, a["stature"], mass=70.0))
    for side in ("r", "l"):
        elbow, wrist = got[f"elbow_{side}"][Z], got[f"wrist_{side}"][Z]
        assert elbow == pytest.approx(a["acromial"] - a["acromion_radiale"], abs=1e-9)
        assert elbow - wrist == pytest.approx(a["radiale_stylion"], abs=1e-9)
        assert 0.0 < a["wrist"] - wrist < 0.015


@pytest.mark.parametrize("sex", ["male", "female"])
def test_limb_segments_span_the_joint_centres(sex: str) -> None:
    """The thigh runs from hip to knee centre, the shank from knee centre to ankle, the upper
    arm from shoulder to elbow centre and the forearm from elbow to wrist centre, their
    centres of mass and radii of gyration at de Leva's fractions of those lengths, their
    masses de Leva's; the builder's records say so."""
    stature, mass = 1.70, 65.0
    a, scale = ANSUR[sex], 1.70 / ANSUR[sex]["stature"]
    hip, knee, ankle = (a[k] * scale for k in ("trochanterion", "knee_mid_patella", "malleolus"))
    shoulder = (a["acromial"] - RAB_GH_BELOW_ACROMION * a["biacromial"]) * scale
    elbow = (a["acromial"] - a["acromion_radiale"]) * scale
    wrist = elbow - a["radiale_stylion"] * scale
    problem = _problem("standing", sex, stature, mass=mass)
    segments = {s.name: s for s in problem.body.segments}
    body = problem.spec.body
    inertia = {
        n: segment_inertia(n, sex=sex, stature=stature, body_mass=mass) for n in human.SEGMENTS
    }
    ranges = {d: (-180.0, 180.0) for d in human.dof_names("standing")}
    records = {r.name: r for r in human.standing(inertia, ranges, body)[1]}
    spans = (
        ("thigh", hip, hip - knee),
        ("shank", knee, knee - ankle),
        ("upper_arm", shoulder, shoulder - elbow),
        ("forearm", elbow, elbow - wrist),
    )
    fractions = DE_LEVA_LEG[sex] | DE_LEVA_ARM[sex]
    for name, top, length in spans:
        com, radii = fractions[name]
        for side in ("r", "l"):
            segment = segments[f"{name}_{side}"]
            assert segment.com[Z] == pytest.approx(top - com * length, abs=1e-9)
            assert segment.mass == pytest.approx(DE_LEVA_MASS[sex][name] * mass, abs=1e-9)
        assert records[f"segment.{name}.length"].value == pytest.approx(length, abs=1e-12)
        assert records[f"segment.{name}.length"].status == "estimate"
        assert records[f"segment.{name}.com_distance"].value == pytest.approx(com * length)
        for axis, fraction in zip(("sagittal", "transverse", "longitudinal"), radii, strict=True):
            record = records[f"segment.{name}.radius_of_gyration.{axis}"]
            assert record.value == pytest.approx(fraction * length, abs=1e-9)
    hip_record = records["body.hip_height"]
    assert hip_record.value == pytest.approx(hip, abs=1e-6)
    assert "trochanterion" in hip_record.source and hip_record.status == "estimate"


def test_a_given_leg_length_moves_the_centres_above() -> None:
    """A problem file's thigh length stands the hips on it (the knee stays at ANSUR's)."""
    a, stature = ANSUR["male"], REFERENCE["male"][0]
    text = _text("standing").replace(
        "[[tasks]]", "[body.segments.thigh]\nlength_m = 0.45\n[[tasks]]"
    )
    got = _landmarks(api.loads(text))
    knee = a["knee_mid_patella"] * stature / a["stature"]
    assert got["knee_r"][Z] == pytest.approx(knee, abs=1e-9)
    assert got["hip_r"][Z] == pytest.approx(knee + 0.45, abs=1e-9)


def test_a_given_forearm_length_moves_the_wrist() -> None:
    """A problem file's forearm length hangs the wrist from the elbow (which stays)."""
    a, stature = ANSUR["male"], REFERENCE["male"][0]
    text = _text("standing").replace(
        "[[tasks]]", "[body.segments.forearm]\nlength_m = 0.30\n[[tasks]]"
    )
    got = _landmarks(api.loads(text))
    elbow = (a["acromial"] - a["acromion_radiale"]) * stature / a["stature"]
    assert got["elbow_r"][Z] == pytest.approx(elbow, abs=1e-9)
    assert got["wrist_l"][Z] == pytest.approx(elbow - 0.30, abs=1e-9)


@pytest.mark.parametrize("model", ["standing", "upper_body"])
def test_a_taller_body_scales_every_centre(model: str) -> None:
    """Geometric similarity: every landmark and the feet's outlines scale with stature."""
    small, tall = _problem(model, "male"), _problem(model, "male", 1.90, mass=95.0)
    ratio = 1.90 / 1.741
    got_small, got_tall = _landmarks(small), _landmarks(tall)
    assert got_small.keys() == got_tall.keys()
    for name, point in got_small.items():
        assert np.max(np.abs(got_tall[name] - ratio * point)) < 1e-9, name
    for foot_small, foot_tall in zip(small.body.feet, tall.body.feet, strict=True):
        outline = np.array(foot_small.outline)
        assert np.max(np.abs(np.array(foot_tall.outline) - ratio * outline)) < 1e-9


def test_seated_upper_body_moves_everything_to_the_hip_height() -> None:
    """``body.hip_height_m`` lifts (or lowers) every landmark of ``upper_body`` alike."""
    standing_hips = _landmarks(_problem("upper_body"))
    seated = api.loads(_text("upper_body").replace("[body]", "[body]\nhip_height_m = 0.5"))
    lift = 0.5 - standing_hips["mid_hip"][2]
    for name, point in _landmarks(seated).items():
        assert np.max(np.abs(point - standing_hips[name] - [0.0, 0.0, lift])) < 1e-9, name


@pytest.mark.parametrize("sex", ["male", "female"])
def test_lumbar_joint_carries_what_is_above_it(sex: str) -> None:
    """The lumbar DOFs carry the trunk parts whose centre of mass is above L5/S1 (head, upper
    and middle trunk) and the arms; the lower trunk, centred below it, stays with the pelvis."""
    for model, pelvis in (("standing", "hip_flexion_r"), ("upper_body", None)):
        problem = _problem(model, sex)
        l5s1 = _landmarks(problem)["l5s1"][Z]
        segments = {s.name: s for s in problem.body.segments}
        for name in ("head_neck", "upper_trunk", "middle_trunk", "lower_trunk"):
            segment = segments[name]
            above = segment.com[Z] > l5s1
            assert above == (name != "lower_trunk"), (model, name, segment.com, l5s1)
            assert (segment.dof == pelvis) != above, (model, name, segment.dof)
        for name, segment in segments.items():
            if segment.mass > 0 and name.startswith(("head", "upper", "middle", "forearm", "hand")):
                assert "lumbar_rotation" in problem.body.ancestors(segment.dof), name


# --- 4. Conventions ------------------------------------------------------------------------

X, Y, Z = 0, 1, 2
# (model, posture [deg], landmark, relative to (landmark, or None: itself at q = 0), axis, sign)
CONVENTIONS = {
    "shoulder flexion r: elbow in front": (
        "upper_body",
        {"shoulder_flexion_r": 90},
        "elbow_r",
        "shoulder_r",
        X,
        +1,
    ),
    "shoulder flexion l: elbow in front": (
        "upper_body",
        {"shoulder_flexion_l": 90},
        "elbow_l",
        "shoulder_l",
        X,
        +1,
    ),
    "shoulder abduction r: elbow to the right": (
        "upper_body",
        {"shoulder_abduction_r": 90},
        "elbow_r",
        "shoulder_r",
        Y,
        -1,
    ),
    "shoulder abduction l: elbow to the left": (
        "upper_body",
        {"shoulder_abduction_l": 90},
        "elbow_l",
        "shoulder_l",
        Y,
        +1,
    ),
    "shoulder internal rotation r: forearm inward": (
        "upper_body",
        {"elbow_flexion_r": 90, "shoulder_rotation_r": 45},
        "wrist_r",
        "elbow_r",
        Y,
        +1,
    ),
    "shoulder internal rotation l: forearm inward": (
        "upper_body",
        {"elbow_flexion_l": 90, "shoulder_rotation_l": 45},
        "wrist_l",
        "elbow_l",
        Y,
        -1,
    ),
    "elbow flexion r: wrist in front": (
        "upper_body",
        {"elbow_flexion_r": 90},
        "wrist_r",
        "elbow_r",
        X,
        +1,
    ),
    "wrist flexion r: palmar, forward with palms forward": (
        "upper_body",
        {"wrist_flexion_r": 60},
        "knuckles_r",
        "wrist_r",
        X,
        +1,
    ),
    "wrist radial deviation r: to the thumb side (lateral)": (
        "upper_body",
        {"wrist_deviation_r": 20},
        "knuckles_r",
        "wrist_r",
        Y,
        -1,
    ),
    "wrist radial deviation l: to the thumb side (lateral)": (
        "upper_body",
        {"wrist_deviation_l": 20},
        "knuckles_l",
        "wrist_l",
        Y,
        +1,
    ),
    "forearm pronation r: palm turns inward": (
        "upper_body",
        {"forearm_pronation_r": 90, "wrist_flexion_r": 60},
        "knuckles_r",
        "wrist_r",
        Y,
        +1,
    ),
    "lumbar flexion: C7 forward": ("upper_body", {"lumbar_flexion": 30}, "c7", None, X, +1),
    "lumbar bending: C7 to the right": ("upper_body", {"lumbar_bending": 20}, "c7", None, Y, -1),
    "lumbar rotation (left): right shoulder forward": (
        "upper_body",
        {"lumbar_rotation": 30},
        "shoulder_r",
        None,
        X,
        +1,
    ),
    "lumbar rotation (left): left shoulder back": (
        "upper_body",
        {"lumbar_rotation": 30},
        "shoulder_l",
        None,
        X,
        -1,
    ),
    "standing lumbar flexion: C7 forward": (
        "standing",
        {"lumbar_flexion": 30},
        "c7",
        None,
        X,
        +1,
    ),
    "hip flexion l: knee forward": ("standing", {"hip_flexion_l": 60}, "knee_l", "hip_l", X, +1),
    "hip abduction l: knee to the left": (
        "standing",
        {"hip_abduction_l": 20},
        "knee_l",
        "hip_l",
        Y,
        +1,
    ),
    "hip internal rotation l, knee bent: foot outward": (
        "standing",
        {"knee_flexion_l": 90, "hip_rotation_l": 30},
        "ankle_l",
        "knee_l",
        Y,
        +1,
    ),
    "knee flexion l: ankle behind the knee": (
        "standing",
        {"knee_flexion_l": 60},
        "ankle_l",
        "knee_l",
        X,
        -1,
    ),
    "ankle dorsiflexion l: toes up": ("standing", {"ankle_flexion_l": 20}, "toe_l", None, Z, +1),
    "ankle inversion l: sole turns inward": (
        "standing",
        {"ankle_inversion_l": 20},
        "heel_l",
        None,
        Y,
        -1,
    ),
    "ankle dorsiflexion r (root foot): shank forward": (
        "standing",
        {"ankle_flexion_r": 20},
        "knee_r",
        None,
        X,
        +1,
    ),
    "ankle dorsiflexion r (root foot): pelvis forward": (
        "standing",
        {"ankle_flexion_r": 20},
        "mid_hip",
        None,
        X,
        +1,
    ),
    "ankle inversion r (root foot): shank leans inward (left)": (
        "standing",
        {"ankle_inversion_r": 20},
        "knee_r",
        "ankle_r",
        Y,
        +1,
    ),
    "knee flexion r (root foot): hips behind the knee": (
        "standing",
        {"knee_flexion_r": 30},
        "mid_hip",
        "knee_r",
        X,
        -1,
    ),
    "hip flexion r (root foot): trunk leans forward": (
        "standing",
        {"hip_flexion_r": 30},
        "c7",
        None,
        X,
        +1,
    ),
    "hip abduction r (root foot): left hip rises": (
        "standing",
        {"hip_abduction_r": 10},
        "hip_l",
        "hip_r",
        Z,
        +1,
    ),
    "hip internal rotation r (root foot): left hip forward": (
        "standing",
        {"hip_rotation_r": 20},
        "hip_l",
        None,
        X,
        +1,
    ),
}


@pytest.fixture(scope="module")
def bodies() -> dict[str, Problem]:
    return {model: _problem(model) for model in ("upper_body", "standing")}


@pytest.mark.parametrize("name", list(CONVENTIONS))
def test_sign_conventions(name: str, bodies: dict[str, Problem]) -> None:
    model, posture, point, relative, axis, sign = CONVENTIONS[name]
    problem = bodies[model]
    moved = _landmarks(problem, _q(problem, **posture))
    base = _landmarks(problem)[point] if relative is None else moved[relative]
    assert sign * (moved[point][axis] - base[axis]) > 0.01, (moved[point], base)


def test_upright_zero_posture(bodies: dict[str, Problem]) -> None:
    """At q = 0 every landmark of a side mirrors the other side's, arms hang (x = 0) and
    the feet of ``standing`` are flat on the floor."""
    for problem in bodies.values():
        points = _landmarks(problem)
        for name, p in points.items():
            if name.endswith("_r"):
                mirror = points[name[:-2] + "_l"]
                assert np.max(np.abs(p - mirror * [1.0, -1.0, 1.0])) < 1e-12, name
            elif not name.endswith("_l"):
                assert abs(p[Y]) < 1e-12, name
    standing = bodies["standing"]
    for foot in standing.body.feet:
        assert np.max(np.abs(np.array(foot.outline)[:, Z])) < 1e-12


# --- 5. Support polygon ------------------------------------------------------------------


def _hand_polygon(sex: str) -> tuple[np.ndarray, float]:
    """The two soles' hull (counter-clockwise) [m] and the centre of mass's x [m] at q = 0,
    from the ANSUR foot, Reed's hip width and de Leva's foot (all other segments hang on
    x = 0)."""
    stature, _ = REFERENCE[sex]
    a = ANSUR[sex]
    ansur = stature / a["stature"]
    length, breadth = a["foot_length"] * ansur, a["foot_breadth"] * ansur
    heel_x = -HEEL_BEHIND_ANKLE * length
    ball_x = heel_x + a["ball_length"] * ansur
    toe_x = heel_x + length
    heel, ball, toe = a["heel_breadth"] * ansur / 2, breadth / 2, TOE_WIDTH * breadth / 2
    y = _expected_centres(sex, stature)["hip_l"][Y]
    hull = [
        (heel_x, -y - heel),
        (ball_x, -y - ball),
        (toe_x, -y - toe),
        (toe_x, y + toe),
        (ball_x, y + ball),
        (heel_x, y + heel),
    ]
    foot_length, foot_com = DE_LEVA_FOOT[sex]
    foot_x = heel_x + foot_com * foot_length * stature / REFERENCE[sex][0]
    com_x = 2 * DE_LEVA_MASS[sex]["foot"] * foot_x / _de_leva_total(sex, legs=True)
    return np.array(hull), com_x


@pytest.mark.parametrize("sex", ["male", "female"])
def test_support_polygon_at_zero_posture(sex: str) -> None:
    problem = _problem("standing", sex)
    body = problem.body
    q = np.zeros(body.n)
    polygon = support.support_polygon(body, q)
    hull, com_x = _hand_polygon(sex)
    assert polygon is not None and len(polygon) == len(hull)
    # The same vertices, counter-clockwise (positive area).
    assert {tuple(np.round(p, 9)) for p in polygon} == {tuple(np.round(p, 9)) for p in hull}
    x, y = polygon[:, 0], polygon[:, 1]
    assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0
    com = np.asarray(ca.Function("com", [body.q], [body.com()])(q)).reshape(-1)
    assert com[X] == pytest.approx(com_x, abs=1e-9)
    assert com[Y] == pytest.approx(0.0, abs=1e-12)

    def edge_distance(point: np.ndarray) -> float:
        """Distance [m] from an inside point to the nearest edge line of the hand hull."""
        distances = []
        for a, b in zip(hull, np.roll(hull, -1, axis=0), strict=True):
            edge = b - a
            distances.append(abs(edge[0] * (point - a)[1] - edge[1] * (point - a)[0]))
            distances[-1] /= np.hypot(*edge)
        return min(distances)

    inside = edge_distance(com[:2])
    # The heel line is the nearest edge: the centre of mass is a few cm in front of it.
    assert inside == pytest.approx(com_x - hull[0][X], abs=1e-12)
    assert support.margin(polygon, com[:2]) == pytest.approx(inside, abs=1e-9)
    # Outside: behind the heels, and beside the right foot's widest point (the ball).
    behind = np.array([hull[0][X] - 0.1, 0.0])
    assert support.margin(polygon, behind) == pytest.approx(-0.1, abs=1e-9)
    beside = hull[1] + [0.0, -0.05]
    assert support.margin(polygon, beside) == pytest.approx(-0.05, abs=1e-9)
