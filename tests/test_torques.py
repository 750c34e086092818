"""External, passive and active torques against hand calculations and energy arguments."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from conftest import PROBLEMS, chain_3d

from casadi_posture.biomech.curve import torque_curve
from casadi_posture.biomech.passive import ExponentialPassive, NoPassive, ReshapedPassive
from casadi_posture.biomech.strength import ConstantStrength, TabulatedStrength
from casadi_posture.biomech.torques import TorqueModel
from casadi_posture.body.loads import Load, pack
from casadi_posture.problem import load_problem

G = 9.81


def _arm():
    return load_problem(PROBLEMS / "holding_m45.toml")


@pytest.mark.parametrize(
    ("qs_deg", "qe_deg"), [(0, 0), (90, 0), (90, 90), (16.88, 77.29), (-45, 120), (150, 30)]
)
def test_sagittal_gravity_torques_by_hand(qs_deg: float, qe_deg: float) -> None:
    """τe of the sagittal arm from moment arms: each weight times its horizontal distance."""
    problem = _arm()
    model = problem.torque_model()
    qs, qe = math.radians(qs_deg), math.radians(qe_deg)
    # reference male, de Leva 1996: lengths, masses, COM distances from the proximal joint
    l_ua, l_fa = 0.2817, 0.2689
    m_ua, m_fa, m_h, m_load = 0.0271 * 73, 0.0162 * 73, 0.0061 * 73, 2.5
    c_ua, c_fa, c_h = 0.5772 * l_ua, 0.4574 * l_fa, 0.7900 * 0.0862
    # horizontal (forward) distance of each weight from the elbow and from the shoulder
    from_elbow = {
        "fa": c_fa * math.sin(qs + qe),
        "h": (l_fa + c_h) * math.sin(qs + qe),
        "load": l_fa * math.sin(qs + qe),
    }
    elbow_x = l_ua * math.sin(qs)
    tau_elbow = -G * (m_fa * from_elbow["fa"] + m_h * from_elbow["h"] + m_load * from_elbow["load"])
    tau_shoulder = -G * m_ua * c_ua * math.sin(qs) + tau_elbow - G * (m_fa + m_h + m_load) * elbow_x
    result = model.evaluate([qs, qe])
    assert result.external == pytest.approx([tau_shoulder, tau_elbow], abs=1e-12)


def test_sanity_values_of_biomech_data() -> None:
    """By hand: arm horizontal, elbow straight: 24.1 and 9.5 N·m; at 90/90: 0, 14.6."""
    model = _arm().torque_model()
    straight = model.evaluate([math.pi / 2, 0.0])
    assert -straight.external == pytest.approx([24.1, 9.5], abs=0.05)
    bent = model.evaluate([math.pi / 2, math.pi / 2])
    assert -bent.external == pytest.approx([14.6, 0.0], abs=0.05)


def _chain_model(loads: list[Load]) -> TorqueModel:
    body = chain_3d()
    passive = {d.name: NoPassive() for d in body.dofs}
    strength = {h.name: ConstantStrength(50.0) for h in body.half_joints}
    return TorqueModel(body, loads, passive, strength)


def test_gravity_torque_is_minus_the_potential_energy_gradient_3d() -> None:
    loads = [Load("weight", "tip", mass=1.7)]
    model = _chain_model(loads)
    body = model.body
    height = sum((s.mass * body.segment_com(s)[2] for s in body.segments), ca.SX(0))
    height += 1.7 * body.landmark("tip")[2]
    energy = ca.Function("V", [body.q], [G * height])
    rng = np.random.default_rng(7)
    for q in rng.uniform(body.lower, body.upper, size=(5, body.n)):
        h = 1e-6
        gradient = [
            (float(energy(q + h * e)) - float(energy(q - h * e))) / (2 * h) for e in np.eye(body.n)
        ]
        assert model.evaluate(q).external == pytest.approx(-np.array(gradient), abs=1e-7)


def test_external_force_and_moment_by_virtual_work_3d() -> None:
    force, moment = (3.0, -2.0, 5.0), (0.4, -1.1, 0.7)
    model = _chain_model([Load("push", "tip", force=force, moment=moment)])
    body = model.body
    without_gravity = _chain_model([Load("push", "tip")])
    tip = ca.Function("x", [body.q], [body.landmark("tip")])
    rot = ca.Function("R", [body.q], [body.rotation("d")])
    rng = np.random.default_rng(8)
    for q in rng.uniform(body.lower, body.upper, size=(4, body.n)):
        tau = model.evaluate(q).external - without_gravity.evaluate(q).external
        h = 1e-6
        for j, e in enumerate(np.eye(body.n)):
            dx = (np.asarray(tip(q + h * e)) - np.asarray(tip(q - h * e))).reshape(-1) / (2 * h)
            skew = (
                (np.asarray(rot(q + h * e)) - np.asarray(rot(q - h * e))) / (2 * h)
            ) @ np.asarray(rot(q)).T
            omega = np.array([skew[2, 1], skew[0, 2], skew[1, 0]])
            assert tau[j] == pytest.approx(np.dot(force, dx) + np.dot(moment, omega), abs=1e-7)


def test_load_parameters_change_torques_without_rebuilding() -> None:
    problem = _arm()
    model = problem.torque_model()
    q = problem.posture
    base = model.evaluate(q)
    heavier = model.evaluate(q, pack([Load("weight", "wrist", mass=5.0)]))
    lever = np.asarray(
        ca.Function("J", [model.body.q], [model.body.jacobian(model.body.landmark("wrist"))])(q)
    )
    assert heavier.external - base.external == pytest.approx(lever.T @ [0, 0, -G * 2.5])


@pytest.mark.parametrize("dof", ["shoulder_flexion", "elbow_flexion"])
def test_default_passive_torque_strictly_decreasing(dof: str) -> None:
    problem = _arm()
    j = problem.body.index[dof]
    angles = np.linspace(problem.body.lower[j], problem.body.upper[j], 2001)
    q = ca.SX.sym("q")
    tau = ca.Function("tp", [q], [problem.passive[dof].expression(q)])
    values = np.asarray(tau(angles)).reshape(-1)
    assert np.all(np.diff(values) < 0)
    assert values[0] > 0 > values[-1]


def _passive_values(problem, dof: str, degrees) -> np.ndarray:
    q = ca.SX.sym("q")
    f = ca.Function("tp", [q], [problem.passive[dof].expression(q)])
    return np.asarray(f(np.radians(np.atleast_1d(degrees)))).ravel()


@pytest.mark.parametrize(
    ("dof", "lower", "upper", "inside"),
    [("shoulder_flexion", -60.0, 180.0, 1.915), ("elbow_flexion", 0.0, 150.0, 1.077)],
)
def test_default_passive_torque_has_measured_magnitudes(
    dof: str, lower: float, upper: float, inside: float
) -> None:
    """The limit-torque default: 5 N·m at each anatomical limit (PredSim's convention), ten
    times less 5 % of the range inside it (5·10^(-5/(0.05·range))), and over the middle
    80 % of the range a stiffness no larger than the 0.4-1.8 N·m/rad measured at the elbow
    (Wiegner & Watts 1986), where the earlier Gymnast fit gave tens of N·m inside the range."""
    problem = _arm()
    at = _passive_values(problem, dof, [lower, lower + 5, upper - 5, upper])
    assert at == pytest.approx([5.0, inside, -inside, -5.0], abs=1e-3)
    assert 5.0 * 10 ** (-5 / (0.05 * (upper - lower))) == pytest.approx(inside, abs=1e-3)
    middle = np.linspace(lower + 0.1 * (upper - lower), upper - 0.1 * (upper - lower), 500)
    stiffness = -np.gradient(_passive_values(problem, dof, middle), np.radians(middle))
    assert 0 < stiffness.max() < 1.8


def test_the_gymnast_fit_is_a_named_alternative(tmp_path) -> None:
    """The earlier default, chosen by name: elbow τp(-10°) = +101, τp(150°) = -70 and
    τp(90°) = -0.014 N·m (1 N·m at the Gymnast zero-passive angles, τ_ISO at the one-norm
    ones)."""
    path = tmp_path / "gymnast.toml"
    path.write_text(
        (PROBLEMS / "holding_m45.toml")
        .read_text()
        .replace(
            "[posture_deg]",
            '[body.dofs.elbow_flexion]\npassive = { model = "gymnast_fit" }\n\n[posture_deg]',
        )
    )
    values = _passive_values(load_problem(path), "elbow_flexion", [-10.0, 150.0, 90.0])
    assert values == pytest.approx([101.0, -70.0, -0.014], rel=0.01, abs=0.001)


def test_the_limit_torque_stays_at_the_anatomical_limits_when_the_range_grows() -> None:
    """frontal_elbow.toml lets the elbow 10° past straight: the tissue's limit stays at 0°,
    so the passive torque rises steeply beyond it (5 N·m at 0°, about 107 N·m at -10°)."""
    values = _passive_values(
        load_problem(PROBLEMS / "frontal_elbow.toml"), "elbow_flexion", [0.0, -10.0]
    )
    assert values[0] == pytest.approx(5.0, abs=1e-9)
    assert values[1] == pytest.approx(5.0 * math.exp(math.log(10) / (0.05 * 150) * 10), rel=1e-9)


@pytest.mark.parametrize("step", [0.0, 2.0])
def test_the_reshaped_passive_curve(step: float) -> None:
    """The paper's reshaping: within 10° of each limit a linear term of 20 N·m/rad (and a
    step) is added toward the middle of the range. Continuous without a step; a jump of
    exactly the step at each band's edge with one; monotonically decreasing either way; and
    the numeric slope the goal algorithm uses matches the expression's."""
    base = ExponentialPassive(5.0, 17.59, 0.0, 5.0, 17.59, math.radians(150))
    model = ReshapedPassive(base, 0.0, math.radians(150), math.radians(10), 20.0, step)
    q = ca.SX.sym("q")
    f = ca.Function("tp", [q], [model.expression(q)])
    grid = np.radians(np.linspace(0, 150, 30001))
    values = np.asarray(f(grid)).ravel()
    assert np.all(np.diff(values) < 0)
    for edge in (math.radians(10), math.radians(140)):
        before, after = float(f(edge - 1e-9)), float(f(edge + 1e-9))
        assert before - after == pytest.approx(step, abs=1e-6)
    inside = math.radians(4)
    expected = float(base.expression(ca.DM(inside))) + step + 20.0 * (math.radians(10) - inside)
    assert float(f(inside)) == pytest.approx(expected, rel=1e-12)
    value, slope = model.numeric(np.array([inside, math.radians(80), math.radians(147)]))
    numeric = np.asarray(
        f([inside + 1e-7, math.radians(80) + 1e-7, math.radians(147) + 1e-7])
    ) - np.asarray(f([inside - 1e-7, math.radians(80) - 1e-7, math.radians(147) - 1e-7]))
    assert slope == pytest.approx(numeric.ravel() / 2e-7, rel=1e-5)
    assert value == pytest.approx(
        np.asarray(f([inside, math.radians(80), math.radians(147)])).ravel()
    )


def test_active_torque_balances_and_half_joints_split_it() -> None:
    problem = _arm()
    result = problem.torque_model().evaluate(problem.posture)
    assert result.active + result.passive + result.external == pytest.approx(0.0, abs=1e-12)
    for i, tau in enumerate(result.active):
        positive, negative = result.half_joint_torque[2 * i : 2 * i + 2]
        assert positive - negative == pytest.approx(tau)
        assert min(positive, negative) == 0.0
    assert result.load_pct_mvc == pytest.approx(100 * result.half_joint_torque / result.strength)


def test_default_strengths_of_biomech_data() -> None:
    """The default strengths of the reference male: 48, 33, 43, 60 N·m (docs/sources.md)."""
    problem = _arm()
    result = problem.torque_model().evaluate(problem.posture)
    assert result.strength == pytest.approx([43.0, 60.1, 47.8, 32.9], abs=0.15)


def test_tabulated_strength_interpolates_and_holds_its_ends() -> None:
    q = ca.SX.sym("q", 2)
    model = TabulatedStrength(1, (0.0, 1.0, 2.0), (40.0, 50.0, 30.0))
    f = ca.Function("st", [q], [model.expression(q)])
    assert float(f([0.0, 0.5])) == pytest.approx(45.0)
    assert float(f([0.0, 1.5])) == pytest.approx(40.0)
    assert float(f([9.0, -1.0])) == pytest.approx(40.0)
    assert float(f([0.0, 3.0])) == pytest.approx(30.0)


def test_frontal_elbow_by_hand_and_three_zero_active_postures() -> None:
    """Fig. 3: forearm and hand weight, τe = -W·cos(q); zeros near each limit and mid-range."""
    problem = load_problem(PROBLEMS / "frontal_elbow.toml")
    model = problem.torque_model()
    moment = 0.0162 * 73 * 0.4574 * 0.2689 + 0.0061 * 73 * (0.2689 + 0.79 * 0.0862)
    for q in np.radians([-10, 0, 30, 90, 135]):
        assert model.evaluate([q]).external[0] == pytest.approx(
            -G * moment * math.cos(q), abs=1e-12
        )
    curve = torque_curve(model, problem.posture, "elbow_flexion")
    kinds = [z.kind for z in curve.zeros]
    assert kinds == ["passive: τp carries τe", "active: τe ≈ 0", "passive: τp carries τe"]
    assert math.degrees(curve.zeros[1].angle) == pytest.approx(90.0, abs=1.0)
    for zero in curve.zeros:
        assert model.evaluate([zero.angle]).active[0] == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("dof", ["shoulder_flexion", "elbow_flexion"])
def test_numeric_passive_torque_and_slope_match_casadi_ad(dof: str) -> None:
    problem = _arm()
    model = problem.passive[dof]
    q = ca.SX.sym("q")
    expr = model.expression(q)
    f = ca.Function("tp", [q], [expr, ca.jacobian(expr, q)])
    angles = np.linspace(
        problem.body.lower[problem.body.index[dof]], problem.body.upper[problem.body.index[dof]], 7
    )
    value, slope = model.numeric(angles)
    for k, angle in enumerate(angles):
        expected = [float(v) for v in f(angle)]
        assert [value[k], slope[k]] == pytest.approx(expected, rel=1e-12, abs=1e-12)


def test_external_torque_jacobian_matches_finite_differences() -> None:
    problem = _arm()
    model = problem.torque_model()
    q = np.radians([30.0, 60.0])
    h = 1e-6
    fd = np.column_stack(
        [
            (model.evaluate(q + h * e).external - model.evaluate(q - h * e).external) / (2 * h)
            for e in np.eye(2)
        ]
    )
    assert model.evaluate(q).external_jacobian == pytest.approx(fd, abs=1e-7)
