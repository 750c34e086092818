"""The low-back model (biomech/low_back.py; docs/low_back.md) against hand calculations,
a published worked example of the same model, finite differences, the torque model and
the shipped problems."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import casadi_posture as cp
from casadi_posture.biomech.low_back import (
    OUTPUTS,
    LowBackModel,
    limits,
    low_back_expressions,
    low_back_model,
)
from casadi_posture.body.loads import Load, pack
from casadi_posture.body.tree import BodyModel, Dof, Landmark, Segment
from casadi_posture.errors import ProblemError
from tests.conftest import PROBLEMS

G = 9.81


def trunk_body(com: tuple[float, float, float], hands: tuple[float, float, float]) -> BodyModel:
    """A pelvis fixed to the world, L5/S1 at (0, 0, 1) m, and one lumbar flexion DOF (about
    +y: positive bends forward) carrying a 40 kg trunk with its centre of mass at ``com`` and
    a landmark ``hands`` [m, zero posture]."""
    dof = Dof(
        "lumbar_flexion", None, (0.0, 0.0, 1.0), (0.0, 1.0, 0.0), -1.0, 2.0, "flexors", "extensors"
    )
    return BodyModel(
        "trunk",
        [dof],
        [Segment("trunk", "lumbar_flexion", 40.0, com)],
        [Landmark("hands", "lumbar_flexion", hands)],
        gravity=G,
    )


def test_hand_calculation_upright_and_flexed() -> None:
    # Trunk 40 kg, its centre of mass 0.02 m ahead of L5/S1 and 0.30 m above it; 10 kg in
    # the hands 0.35 m ahead and 0.25 m above L5/S1; erector spinae moment arm E = 0.05 m.
    # Upright:
    #   extensor moment M = 40·9.81·0.02 + 10·9.81·0.35 = 7.848 + 34.335 = 42.183 N·m
    #   muscle force  F_m = M / E = 42.183 / 0.05 = 843.66 N
    #   compression   C = F_m + (40 + 10)·9.81 = 843.66 + 490.5 = 1334.16 N, shear 0.
    # Flexed 30°: a point (x, z) above L5/S1 moves to x' = x cos 30° + z sin 30°:
    #   trunk x' = 0.02·0.86603 + 0.30·0.5 = 0.167321 m, hands x' = 0.35·0.86603 + 0.25·0.5
    #   = 0.428109 m; M = 392.4·0.167321 + 98.1·0.428109 = 65.657 + 41.998 = 107.655 N·m;
    #   F_m = 2153.1 N; C = 2153.1 + 490.5·cos 30° = 2153.1 + 424.79 = 2577.9 N;
    #   shear = 490.5·sin 30° = 245.25 N forward.
    body = trunk_body((0.02, 0.0, 1.30), (0.35, 0.0, 1.25))
    model = LowBackModel(body, [Load("box", "hands", mass=10.0)])
    upright = model.evaluate([0.0])
    assert upright.sagittal_moment == pytest.approx(42.183, abs=1e-3)
    assert upright.muscle_force == pytest.approx(843.66, abs=1e-2)
    assert upright.compression == pytest.approx(1334.16, abs=1e-2)
    assert upright.shear == pytest.approx(0.0, abs=1e-9)
    flexed = model.evaluate([np.radians(30.0)])
    assert flexed.sagittal_moment == pytest.approx(107.655, abs=2e-3)
    assert flexed.compression == pytest.approx(2577.9, abs=0.1)
    assert flexed.shear == pytest.approx(245.25, abs=1e-2)
    assert flexed.lateral_shear == pytest.approx(0.0, abs=1e-9)


def test_extending_moment_takes_the_abdominal_moment_arm() -> None:
    # The trunk's centre of mass 0.05 m behind L5/S1, no load: M = −40·9.81·0.05 = −19.62 N·m,
    # carried by the rectus abdominis at 0.098 m: F_m = 200.2 N, C = 200.2 + 392.4 = 592.6 N.
    model = LowBackModel(trunk_body((-0.05, 0.0, 1.30), (0.0, 0.0, 1.3)), [])
    out = model.evaluate([0.0])
    assert out.sagittal_moment == pytest.approx(-19.62)
    assert out.muscle_force == pytest.approx(19.62 / 0.098)
    assert out.compression == pytest.approx(19.62 / 0.098 + 392.4)


def test_published_worked_example() -> None:
    # https://homeworksource.com/p/1067204 (the single-equivalent-muscle model, E = 0.05 m):
    # upper body 450 N at 0.25 m and a load of 200 N at 0.4 m ahead of L5/S1, the spine 35°
    # from vertical: F_m = 3850 N, compression 4382.4 N, shear 372.8 N. Our trunk leans 35°
    # with its centre of mass and the hands on the spine's line, at 0.25 and 0.4 m ahead.
    s = np.sin(np.radians(35.0))
    body = trunk_body((0.0, 0.0, 1.0 + 0.25 / s), (0.0, 0.0, 1.0 + 0.4 / s))
    body = BodyModel(
        "example",
        body.dofs,
        [Segment("trunk", "lumbar_flexion", 450.0 / G, body.segments[0].com)],
        list(body.landmarks.values()),
        gravity=G,
    )
    out = LowBackModel(body, [Load("load", "hands", mass=200.0 / G)]).evaluate([np.radians(35)])
    assert out.muscle_force == pytest.approx(3850.0, abs=0.5)
    assert out.compression == pytest.approx(4382.4, abs=0.5)
    assert out.shear == pytest.approx(372.8, abs=0.5)


def _problem(name: str) -> cp.Problem:
    return cp.load(PROBLEMS / f"{name}.toml")


def test_load_in_the_hands_of_the_3d_body() -> None:
    # upper_body upright, arms hanging: 10 kg more at the right grip, x_g ahead of L5/S1,
    # adds 98.1·x_g N·m to the moment, 98.1·x_g / 0.05 N to the muscle and 98.1 N more.
    problem = _problem("seated_assembly")
    body = problem.body
    q = np.zeros(body.n)
    model = LowBackModel(body, [Load("box", "grip_r", mass=1.0)])
    empty, loaded = (
        model.evaluate(q, pack([Load("box", "grip_r")])),
        model.evaluate(q, pack([Load("box", "grip_r", mass=10.0)])),
    )
    grip = ca.Function("g", [body.q], [body.landmark("grip_r") - body.landmark("l5s1")])
    ahead = float(grip(q)[0])
    assert loaded.sagittal_moment - empty.sagittal_moment == pytest.approx(98.1 * ahead)
    extra = loaded.compression - empty.compression
    assert extra == pytest.approx(98.1 * ahead / 0.05 + 98.1)


@pytest.mark.parametrize("name", ["seated_assembly", "standing_shelf_box"])
def test_sagittal_moment_is_the_lumbar_flexion_torque(name: str) -> None:
    # With no lateral bending or twist the trunk's y axis is the flexion axis: the model's
    # moment equals the external lumbar flexion torque of biomech/torques.py.
    problem = _problem(name)
    body = problem.body
    rng = np.random.default_rng(3)
    q = rng.uniform(0.3 * body.lower, 0.3 * body.upper)
    q[body.index["lumbar_bending"]] = q[body.index["lumbar_rotation"]] = 0.0
    torque = problem.torque_model().evaluate(q).external[body.index["lumbar_flexion"]]
    out = LowBackModel(body, problem.loads).evaluate(q)
    assert out.sagittal_moment == pytest.approx(torque, rel=1e-9, abs=1e-9)


def test_derivatives_match_finite_differences() -> None:
    problem = _problem("standing_shelf_box")
    body = problem.body
    model = LowBackModel(body, problem.loads)
    p = model.default_loads
    rng = np.random.default_rng(7)
    q = rng.uniform(0.3 * body.lower, 0.3 * body.upper)
    q[body.index["lumbar_flexion"]] = np.radians(25.0)
    out = ca.vertcat(*model.function(body.q, p))
    jacobian = ca.Function("j", [body.q], [ca.jacobian(out, body.q)])(q).full()
    f = ca.Function("f", [body.q], [out])
    h = 1e-6
    for j in range(body.n):
        dq = np.zeros(body.n)
        dq[j] = h
        column = (f(q + dq).full() - f(q - dq).full()).ravel() / (2 * h)
        np.testing.assert_allclose(jacobian[:, j], column, rtol=1e-6, atol=1e-4)
    assert np.abs(jacobian[0]).max() > 100.0  # the compression does depend on the posture


def test_moment_arms_may_be_symbols() -> None:
    # Sensitivities differentiate with respect to the model's parameters too:
    # ∂C/∂E = −M/E² when the extensors act.
    problem = _problem("seated_assembly")
    e, a = ca.SX.sym("E"), ca.SX.sym("A")
    p = pack(problem.loads)
    out = low_back_expressions(problem.body, problem.loads, ca.DM(p), e, a)
    q = problem.posture
    f = ca.Function("f", [problem.body.q, e, a], [out[0], ca.gradient(out[0], e), out[3]])
    compression, d_e, moment = (float(v) for v in f(q, 0.05, 0.098))
    assert moment > 0
    assert d_e == pytest.approx(-moment / 0.05**2)
    assert compression == pytest.approx(
        LowBackModel(problem.body, problem.loads).evaluate(q).compression
    )


def test_no_lumbar_joint_no_model() -> None:
    problem = _problem("holding_horizontal")
    assert low_back_model(problem.body, problem.loads) is None
    with pytest.raises(ProblemError, match="lumbar joint"):
        LowBackModel(problem.body, problem.loads)


def test_limits() -> None:
    assert limits() == {"design": 3400.0, "upper": 6400.0}


@pytest.mark.parametrize(
    "name",
    [
        "standing_shelf_box",
        "seated_assembly",
        "standing_wall_horizontal",
        "standing_overhead_drill",
    ],
)
def test_shipped_start_postures(name: str) -> None:
    # Upright with at most 6 kg in the hands: more than the weight above L5/S1, well below
    # the design limit, no shear (the trunk is vertical and symmetric at the start).
    problem = _problem(name)
    model = low_back_model(problem.body, problem.loads)
    assert model is not None
    out = model.evaluate(problem.posture)
    assert all(np.isfinite(getattr(out, k)) for k in OUTPUTS)
    assert out.sagittal_moment > 0
    above = out.compression - out.muscle_force - sum(load.mass for load in problem.loads) * G
    weight = problem.spec.body.mass_kg * G
    assert 0.4 * weight < above < 0.6 * weight  # head, arms and most of the trunk
    assert 400.0 < out.compression < limits()["design"]
    assert out.shear == pytest.approx(0.0, abs=1e-6)


@pytest.mark.parametrize(
    ("mass", "trunk", "load", "compression", "shear"),
    [(73.0, 35.0, 200.0 / G, 2852.0, 316.4), (81.14, 60.0, 20.0, 4035.0, 508.4)],
)
def test_published_cases_on_our_body(
    mass: float, trunk: float, load: float, compression: float, shear: float
) -> None:
    # docs/low_back.md's comparison table, "ours, arms hanging": upper_body flexed by
    # `trunk`, both arms hanging vertically (shoulder flexion = trunk flexion), `load` kg
    # shared by the hands.
    problem = cp.load(PROBLEMS / "seated_assembly.toml", overrides={"body.mass_kg": mass})
    body = problem.body
    q = np.zeros(body.n)
    q[body.index["lumbar_flexion"]] = np.radians(trunk)
    for side in "rl":
        q[body.index[f"shoulder_flexion_{side}"]] = np.radians(trunk)
    loads = [Load(side, f"grip_{side}", mass=load / 2) for side in "rl"]
    out = LowBackModel(body, loads).evaluate(q)
    assert out.compression == pytest.approx(compression, abs=1.0)
    assert out.shear == pytest.approx(shear, abs=0.1)
