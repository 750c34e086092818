"""The benchmark bodies: humanoid trees of 2, 7, 14, 28 and 42 DOF as problem files.

Run: python benchmarks/trees.py   (rewrites benchmarks/problems/humanoid_<n>.toml and
prints, per body and start, both solvers' statuses and how far their level residuals are
apart; benchmarks/scaling.py measures more)

World frame: x forward, y to the subject's left, z up, the pelvis fixed with the hip
centres 0.90 m above the floor. Zero posture: standing upright, arms hanging. Every
3-DOF joint is flexion, then abduction (bending), then rotation about the segment. The
trees and their tasks:

- 2: right shoulder and elbow flexion; wrist position ▸ comfort;
- 7: a right arm (shoulder 3, elbow, forearm, wrist 2); wrist ▸ comfort;
- 14: both arms; both wrists ▸ comfort;
- 28: lumbar flexion and bending, both arms, both legs (hip 3, knee, ankle 2);
  ankles ▸ centre of mass over the feet (x, y) ▸ wrists ▸ comfort;
- 42: lumbar and thoracic spine (3 + 3), neck and head (3 + 3), clavicles (2 + 2),
  both arms and legs; the same four levels.

Targets are the forward kinematics of a random posture (seeded by n), within the middle
half of every limb's range, the trunk, neck and shoulder girdle near upright, so every
level above the last is reachable. The last level is the comfort measure of the shipped
3-D problems (docs/comfort.md: displacement from the upright neutral posture, discomfort
near the limits, effort), which settles whatever the levels above leave free. Segment masses are
rough de Leva (1996) shares of 73 kg and strengths rough adult values: these bodies
measure speed, not people.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from casadi_posture.body.tree import BodyModel
from casadi_posture.data import parameters
from casadi_posture.data.parameters import data_name
from casadi_posture.ik.lexicographic import LexicographicSolver
from casadi_posture.ik.nullspace import NullspaceSolver
from casadi_posture.problem import Problem, problem_from_data

HERE = Path(__file__).resolve().parent / "problems"
SIZES = (2, 7, 14, 28, 42)

# name suffix -> (axis for the right side, mirrored for the left?), range [deg], region,
# strength of the positive and negative groups [N·m], their names
_FLEX = (0.0, -1.0, 0.0)
_TRUNK_FLEX = (0.0, 1.0, 0.0)


def _mirror(axis: tuple[float, float, float], side: str, flip: tuple[bool, bool, bool]) -> list:
    """``axis`` of the right side, or of the left one with the components in ``flip`` negated."""
    if side == "r":
        return list(axis)
    return [-c if f else c for c, f in zip(axis, flip, strict=True)]


class _Builder:
    """Collects DOFs, segments and landmarks in problem-file form."""

    def __init__(self) -> None:
        self.dofs: list[dict[str, Any]] = []
        self.segments: list[dict[str, Any]] = []
        self.landmarks: list[dict[str, Any]] = []

    def dof(
        self,
        name: str,
        parent: str | None,
        origin: list[float],
        axis: list[float],
        range_deg: tuple[float, float],
        region: str,
        groups: tuple[str, str],
        strengths: tuple[float, float],
    ) -> str:
        entry: dict[str, Any] = {"name": name}
        if parent is not None:
            entry["parent"] = parent
        entry |= {
            "origin_m": [round(v, 4) for v in origin],
            "axis": axis,
            "range_deg": list(range_deg),
            # The limit torque at this body's own range: its conventions are not the shipped
            # ones of DOFs of the same names.
            "passive": {
                "model": "limit_torque",
                "lower_deg": range_deg[0],
                "upper_deg": range_deg[1],
            },
            "positive": {"name": groups[0], "strength_Nm": strengths[0], "region": region},
            "negative": {"name": groups[1], "strength_Nm": strengths[1], "region": region},
        }
        self.dofs.append(entry)
        return name

    def joint3(
        self,
        prefix: str,
        parent: str | None,
        origin: list[float],
        axes: tuple[list[float], list[float], list[float]],
        ranges: tuple[tuple[float, float], ...],
        region: str,
        strength: float,
    ) -> str:
        """Flexion, abduction (bending, for the spine: no side) and rotation about one
        centre; the name of the last DOF."""
        side = prefix[-1] if prefix[-2:] in ("_r", "_l") else ""
        base, suffix = (prefix[:-2], prefix[-2:]) if side else (prefix, "")
        kinds = (
            ("flexion", "flexors", "extensors"),
            ("abduction", "abductors", "adductors") if side else ("bending", "left", "right"),
            ("rotation", "internal_rotators", "external_rotators"),
        )
        for (kind, up, down), axis, rng, share in zip(
            kinds, axes, ranges, (1.0, 0.8, 0.5), strict=True
        ):
            parent = self.dof(
                f"{base}_{kind}{suffix}",
                parent,
                origin,
                axis,
                rng,
                region,
                (f"{base}_{up}{suffix}", f"{base}_{down}{suffix}"),
                (strength * share, strength * share),
            )
        return parent

    def segment(self, name: str, dof: str | None, mass: float, com: list[float]) -> None:
        entry: dict[str, Any] = {"name": name}
        if dof is not None:
            entry["dof"] = dof
        entry |= {"mass_kg": mass, "com_m": [round(v, 4) for v in com]}
        self.segments.append(entry)

    def landmark(self, name: str, dof: str | None, position: list[float]) -> None:
        entry: dict[str, Any] = {"name": name}
        if dof is not None:
            entry["dof"] = dof
        entry["position_m"] = [round(v, 4) for v in position]
        self.landmarks.append(entry)


def _arm(b: _Builder, side: str, parent: str | None, shoulder: list[float], full: bool) -> None:
    """A 7-DOF arm hanging from ``shoulder`` (2 DOF, flexions only, when not ``full``)."""
    y, z = shoulder[1], shoulder[2]
    elbow, wrist, tip = [0.0, y, z - 0.30], [0.0, y, z - 0.55], [0.0, y, z - 0.64]
    s = f"_{side}"
    if full:
        upper = b.joint3(
            f"shoulder{s}",
            parent,
            shoulder,
            (list(_FLEX), _mirror((-1.0, 0.0, 0.0), side, (True, False, False)), [0, 0, 1.0]),
            ((-60, 180), (-30, 180), (-90, 70)),
            "shoulder",
            100.0,
        )
    else:
        upper = b.dof(
            f"shoulder_flexion{s}",
            parent,
            shoulder,
            list(_FLEX),
            (-60, 180),
            "shoulder",
            (f"shoulder_flexors{s}", f"shoulder_extensors{s}"),
            (60.0, 50.0),
        )
    b.segment(f"upper_arm{s}", upper, 2.0, [0.0, y, z - 0.17])
    b.landmark(f"elbow{s}", upper, elbow)
    fore = b.dof(
        f"elbow_flexion{s}",
        upper,
        elbow,
        list(_FLEX),
        (0, 150),
        "elbow",
        (f"elbow_flexors{s}", f"elbow_extensors{s}"),
        (70.0, 45.0),
    )
    if full:
        fore = b.dof(
            f"forearm_pronation{s}",
            fore,
            elbow,
            [0.0, 0.0, 1.0],
            (-80, 80),
            "elbow",
            (f"pronators{s}", f"supinators{s}"),
            (8.0, 9.0),
        )
    b.segment(f"forearm{s}", fore, 1.2, [0.0, y, z - 0.42])
    b.landmark(f"wrist{s}", fore, wrist)
    hand = fore
    if full:
        hand = b.dof(
            f"wrist_flexion{s}",
            fore,
            wrist,
            list(_FLEX),
            (-70, 80),
            "hand",
            (f"wrist_flexors{s}", f"wrist_extensors{s}"),
            (12.0, 8.0),
        )
        hand = b.dof(
            f"wrist_deviation{s}",
            hand,
            wrist,
            _mirror((1.0, 0.0, 0.0), side, (True, False, False)),
            (-20, 30),
            "hand",
            (f"radial_deviators{s}", f"ulnar_deviators{s}"),
            (10.0, 10.0),
        )
    b.segment(f"hand{s}", hand, 0.45, [0.0, y, z - 0.61])
    b.landmark(f"knuckles{s}", hand, tip)


def _leg(b: _Builder, side: str) -> None:
    """A 6-DOF leg from the fixed pelvis: hip 3, knee, ankle flexion and inversion."""
    y = 0.09 if side == "l" else -0.09
    s = f"_{side}"
    thigh = b.joint3(
        f"hip{s}",
        None,
        [0.0, y, 0.90],
        (list(_FLEX), _mirror((-1.0, 0.0, 0.0), side, (True, False, False)), [0, 0, 1.0]),
        ((-20, 120), (-25, 45), (-40, 40)),
        "general",
        150.0,
    )
    b.segment(f"thigh{s}", thigh, 10.4, [0.0, y, 0.72])
    b.landmark(f"knee{s}", thigh, [0.0, y, 0.50])
    shank = b.dof(
        f"knee_flexion{s}",
        thigh,
        [0.0, y, 0.50],
        [0.0, 1.0, 0.0],
        (0, 150),
        "knee",
        (f"knee_flexors{s}", f"knee_extensors{s}"),
        (100.0, 180.0),
    )
    b.segment(f"shank{s}", shank, 3.2, [0.0, y, 0.31])
    b.landmark(f"ankle{s}", shank, [0.0, y, 0.08])
    foot = b.dof(
        f"ankle_flexion{s}",
        shank,
        [0.0, y, 0.08],
        list(_FLEX),
        (-20, 45),
        "ankle",
        (f"dorsiflexors{s}", f"plantarflexors{s}"),
        (40.0, 120.0),
    )
    foot = b.dof(
        f"ankle_inversion{s}",
        foot,
        [0.0, y, 0.08],
        [1.0, 0.0, 0.0] if side == "l" else [-1.0, 0.0, 0.0],
        (-20, 30),
        "ankle",
        (f"invertors{s}", f"evertors{s}"),
        (30.0, 25.0),
    )
    b.segment(f"foot{s}", foot, 1.0, [0.05, y, 0.04])
    b.landmark(f"toe{s}", foot, [0.18, y, 0.0])


def _spine(b: _Builder, n: int) -> str:
    """The trunk from the pelvis up; the DOF that carries the shoulders."""
    trunk = (list(_TRUNK_FLEX), [1.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    b.segment("pelvis", None, 8.2, [0.0, 0.0, 0.95])
    if n == 28:
        lumbar = b.dof(
            "lumbar_flexion", None, [0, 0, 1.05], trunk[0], (-30, 80), "trunk",
            ("lumbar_flexors", "lumbar_extensors"), (250.0, 300.0),
        )  # fmt: skip
        lumbar = b.dof(
            "lumbar_bending", lumbar, [0, 0, 1.05], trunk[1], (-30, 30), "trunk",
            ("lumbar_left", "lumbar_right"), (240.0, 240.0),
        )  # fmt: skip
        b.segment("trunk", lumbar, 30.0, [0.0, 0.0, 1.30])
        b.segment("head", lumbar, 5.1, [0.0, 0.0, 1.62])
        return lumbar
    limits = ((-30, 80), (-30, 30), (-40, 40))
    lumbar = b.joint3("lumbar", None, [0, 0, 1.05], trunk, limits, "trunk", 300.0)
    b.segment("abdomen", lumbar, 11.7, [0.0, 0.0, 1.15])
    thoracic = b.joint3("thoracic", lumbar, [0, 0, 1.25], trunk, limits, "trunk", 250.0)
    b.segment("thorax", thoracic, 18.0, [0.0, 0.0, 1.38])
    neck = b.joint3("neck", thoracic, [0, 0, 1.50], trunk, ((-40, 60),) * 3, "general", 60.0)
    b.segment("neck", neck, 1.0, [0.0, 0.0, 1.54])
    head = b.joint3("head", neck, [0, 0, 1.58], trunk, ((-20, 20),) * 3, "general", 40.0)
    b.segment("head", head, 4.1, [0.0, 0.0, 1.66])
    b.landmark("head_top", head, [0.0, 0.0, 1.75])
    return thoracic


def _clavicle(b: _Builder, side: str, parent: str) -> str:
    y = 0.02 if side == "l" else -0.02
    s = f"_{side}"
    elevation = b.dof(
        f"clavicle_elevation{s}",
        parent,
        [0.0, y, 1.42],
        _mirror((-1.0, 0.0, 0.0), side, (True, False, False)),
        (-10, 40),
        "shoulder",
        (f"shoulder_elevators{s}", f"shoulder_depressors{s}"),
        (150.0, 120.0),
    )
    protraction = b.dof(
        f"clavicle_protraction{s}",
        elevation,
        [0.0, y, 1.42],
        [0.0, 0.0, -1.0] if side == "l" else [0.0, 0.0, 1.0],
        (-20, 30),
        "shoulder",
        (f"protractors{s}", f"retractors{s}"),
        (100.0, 100.0),
    )
    b.segment(f"clavicle{s}", protraction, 0.2, [0.0, 2 * y + (0.08 if y > 0 else -0.08), 1.42])
    return protraction


def tree(n: int) -> dict[str, Any]:
    """The ``body.tree`` table of the n-DOF benchmark body (n in ``SIZES``)."""
    b = _Builder()
    if n in (2, 7):
        b.segment("torso", None, 35.0, [0.0, 0.0, 1.20])
        _arm(b, "r", None, [0.0, -0.18, 1.42], full=n == 7)
    elif n == 14:
        b.segment("torso", None, 35.0, [0.0, 0.0, 1.20])
        for side, y in (("r", -0.18), ("l", 0.18)):
            _arm(b, side, None, [0.0, y, 1.42], full=True)
    elif n in (28, 42):
        top = _spine(b, n)
        for side, y in (("r", -0.18), ("l", 0.18)):
            parent = _clavicle(b, side, top) if n == 42 else top
            _arm(b, side, parent, [0.0, y, 1.42], full=True)
            _leg(b, side)
    else:
        raise ValueError(f"no benchmark tree of {n} DOF: one of {SIZES}")
    data = {"name": f"humanoid_{n}", "dofs": b.dofs, "segments": b.segments}
    data["landmarks"] = b.landmarks
    if len(b.dofs) != n:
        raise AssertionError(f"the {n}-DOF tree has {len(b.dofs)} DOFs")
    return data


def _levels(n: int) -> list[tuple[str, list[str]]]:
    """(task kind, effectors) per priority level above the comfort level."""
    wrists = ["wrist_r"] if n in (2, 7) else ["wrist_r", "wrist_l"]
    if n < 28:
        return [("position", wrists)]
    return [("position", ["ankle_r", "ankle_l"]), ("com", []), ("position", wrists)]


def _comfort(body: BodyModel) -> dict[str, Any]:
    """The comfort task's own neutral angles [deg] and joint weights for the DOFs the shipped
    comfort data do not cover (thoracic spine, neck, head, clavicles): upright (0, clipped
    into the range), weight 1, as the shipped data take every DOF they cover."""
    table = parameters.load("comfort")
    missing = [d for d in body.dofs if f"comfort.neutral.{data_name(d.name)}" not in table]
    if not missing:
        return {}
    return {
        "neutral_deg": {
            d.name: round(math.degrees(min(max(0.0, d.lower), d.upper)), 6) for d in missing
        },
        "joint_weights": {d.name: 1.0 for d in missing},
    }


def problem_data(n: int) -> dict[str, Any]:
    """The whole problem file of the n-DOF benchmark: its tree, its tasks with reachable
    targets, 20 minutes of simulated hold with a 1 kg load in the right hand."""
    body_tree = tree(n)
    draft = {"body": {"tree": body_tree}}
    body = problem_from_data(draft, f"humanoid_{n}").body
    rng = np.random.default_rng(n)
    middle, half = (body.lower + body.upper) / 2, (body.upper - body.lower) / 2
    limbs = np.array(
        [d.name.endswith(("_r", "_l")) and "clavicle" not in d.name for d in body.dofs]
    )
    upright = np.clip(np.zeros(body.n), body.lower, body.upper)
    centre = np.where(limbs, middle, upright)  # the trunk, neck and shoulder girdle upright
    spread = np.where(limbs, 0.5, 0.05) * half
    q_target = np.clip(centre + spread * rng.uniform(-1.0, 1.0, body.n), body.lower, body.upper)
    names = list(body.landmarks)
    at_target = ca.Function("at", [body.q], [body.com(), *map(body.landmark, names)])(q_target)
    com, *where = ([float(v) for v in np.asarray(x).ravel()] for x in at_target)
    points = dict(zip(names, where, strict=True))
    tasks: list[dict[str, Any]] = []
    for priority, (kind, effectors) in enumerate(_levels(n), start=1):
        if kind == "com":
            target = [round(v, 6) for v in com]
            tasks.append(
                {"name": "balance", "kind": "com", "priority": priority, "axes": "xy"}
                | {"target_m": target, "include_loads": False}
            )
        for effector in effectors:
            tasks.append(
                {"name": f"hold_{effector}", "kind": "position", "priority": priority}
                | {"effector": effector, "target_m": [round(v, 6) for v in points[effector]]}
            )
    tasks.append(
        {"name": "comfort", "kind": "comfort", "priority": len(_levels(n)) + 1} | _comfort(body)
    )
    return {
        "title": f"Benchmark humanoid, {n} DOF",
        "description": "Generated by benchmarks/trees.py; targets from a random posture.",
        "body": {"tree": body_tree},
        "posture_deg": {
            d.name: round(math.degrees(v), 6) for d, v in zip(body.dofs, q_target, strict=True)
        },
        "loads": [{"name": "object", "at": "wrist_r", "mass_kg": 1.0}],
        "tasks": tasks,
        "fatigue": {"endurance": "frey_law_avin"},
        "simulation": {"duration_s": 1200.0, "time_step_s": 1.0},
    }


def load(n: int) -> Problem:
    """The shipped benchmark problem of n DOF, read from ``benchmarks/problems``."""
    from casadi_posture.problem import load_problem

    return load_problem(HERE / f"humanoid_{n}.toml")


def agreement(problem: Problem) -> list[str]:
    """Per start (the file's posture, the targets' own; upright, the zero posture clipped
    into the ranges): each solver's status and the largest difference of their level
    residuals (task units)."""
    hierarchy, body = problem.hierarchy(), problem.body
    ns, lx = NullspaceSolver(hierarchy), LexicographicSolver(hierarchy)
    upright = np.clip(np.zeros(body.n), body.lower, body.upper)
    lines = []
    for name, start in (("file", problem.posture), ("upright", upright)):
        a, b = ns.solve(start), lx.solve(start)
        apart = float(np.max(np.abs(a.residuals - b.residuals)))
        lines.append(
            f"  from {name}: nullspace {a.status}, lexicographic {b.status}, {apart:.2g} apart"
        )
    return lines


def _value(value: Any) -> str:
    """A TOML value: a string, number, array, or a table of those written inline."""
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_value(v)}" for k, v in value.items()) + " }"
    if isinstance(value, list):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    return json.dumps(value)


def to_toml(table: dict[str, Any], prefix: str = "") -> str:
    """``table`` as TOML: plain keys and small tables inline, then sub-tables, then arrays of
    tables (what the benchmark problems hold)."""
    inline = {k: v for k, v in table.items() if _is_inline(v)}
    lines = [f"{k} = {_value(v)}" for k, v in inline.items()]
    for key, value in table.items():
        name = f"{prefix}.{key}" if prefix else key
        if isinstance(value, dict) and key not in inline:
            lines += ["", f"[{name}]", to_toml(value, name)]
        elif isinstance(value, list) and key not in inline:
            for item in value:
                lines += ["", f"[[{name}]]", to_toml(item, name)]
    return "\n".join(lines).strip("\n")


def _is_inline(value: Any) -> bool:
    if isinstance(value, list):
        return not any(isinstance(v, dict) for v in value)
    if isinstance(value, dict):
        return len(value) <= 3 and not any(isinstance(v, dict | list) for v in value.values())
    return True


def main() -> None:
    HERE.mkdir(exist_ok=True)
    for n in SIZES:
        path = HERE / f"humanoid_{n}.toml"
        header = "# Generated by benchmarks/trees.py: edit that, not this."
        text = f"{header}\n{to_toml(problem_data(n))}\n"
        path.write_text(text, encoding="utf-8")
        problem = load(n)
        print(
            f"{path.relative_to(HERE.parents[1])}: {problem.body.n} DOF, "
            f"{problem.hierarchy().depth} levels, {problem.body.total_mass:.1f} kg"
        )
        print("\n".join(agreement(problem)))


if __name__ == "__main__":
    main()
