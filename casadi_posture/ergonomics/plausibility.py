"""How plausible a posture is for a person: joints near or at a limit, the displacement
from the neutral posture, left/right asymmetry where the task is symmetric, motion out of
the task's plane, and what the idle limbs do; flags where a source calls a posture
uncomfortable or extreme (data/plausibility.toml, docs/plausibility.md)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from casadi_posture.body.loads import Load
from casadi_posture.body.tree import BodyModel
from casadi_posture.data import parameters
from casadi_posture.ergonomics.mirror import asymmetry, lateral, symmetric
from casadi_posture.ik.tasks import Gaze, Line, Orientation, Plane, Position, Task
from casadi_posture.spec.sides import sided_pairs


def _value(name: str) -> float:
    return float(parameters.value("plausibility", name))


@dataclass(frozen=True)
class NearLimit:
    """A DOF within the near-limit zone: its angle and the limit [deg], which one, and its
    distance from it [% of the range]."""

    dof: str
    angle_deg: float
    limit_deg: float
    side: str
    distance_pct: float

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


@dataclass(frozen=True)
class PostureCheck:
    """The report of one posture (``label`` start, recovery or end, at ``time_s``)."""

    label: str
    time_s: float | None
    near_limits: tuple[NearLimit, ...]
    displacement: float | None
    farthest: tuple[str, float] | None
    asymmetry_deg: float | None
    asymmetric_dof: str | None
    out_of_plane_deg: float | None
    out_of_plane_dof: str | None
    idle: tuple[tuple[str, str, float], ...]
    flags: tuple[str, ...] = field(default=())

    def to_dict(self) -> dict[str, Any]:
        """Plain data, angles in degrees (None: not applicable to this task)."""
        return {
            "label": self.label,
            "time_s": self.time_s,
            "near_limits": [n.to_dict() for n in self.near_limits],
            "displacement_from_neutral": self.displacement,
            "farthest_from_neutral": None
            if self.farthest is None
            else {"dof": self.farthest[0], "deg": self.farthest[1]},
            "asymmetry_deg": self.asymmetry_deg,
            "asymmetric_dof": self.asymmetric_dof,
            "out_of_plane_deg": self.out_of_plane_deg,
            "out_of_plane_dof": self.out_of_plane_dof,
            "idle_limbs": [
                {"limb": limb, "dof": dof, "from_neutral_deg": deg} for limb, dof, deg in self.idle
            ],
            "flags": list(self.flags),
            "summary": self.line(),
        }

    def line(self) -> str:
        """One line for the console."""
        parts = [
            f"{len(self.near_limits)} joint(s) near a limit"
            + (f" ({', '.join(n.dof for n in self.near_limits)})" if self.near_limits else "")
        ]
        if self.farthest is not None:
            parts.append(f"farthest from neutral {self.farthest[0]} {self.farthest[1]:+.0f}°")
        if self.asymmetry_deg is not None:
            parts.append(f"left/right {self.asymmetry_deg:.1f}° apart")
        if self.out_of_plane_deg is not None:
            parts.append(f"out of the task's plane {self.out_of_plane_deg:.1f}°")
        for limb, dof, deg in self.idle:
            parts.append(f"idle {limb} {deg:.0f}° from neutral ({dof})")
        time = "" if self.time_s is None else f" ({self.time_s:g} s)"
        return f"{self.label}{time}: " + "; ".join(parts)


class Plausibility:
    """The plausibility checks of one problem's body, tasks and loads, prepared once:
    whether the task is mirror-symmetric, which DOFs move the task's effectors out of its
    plane, which limbs are idle, and the compiled positions of the effectors."""

    def __init__(
        self,
        body: BodyModel,
        tasks: Sequence[Task],
        loads: Sequence[Load],
        neutral: np.ndarray | None,
    ) -> None:
        self.body = body
        self.neutral = neutral
        self.symmetric = symmetric(body, tasks, loads)
        effectors = sorted(
            {t.effector for t in tasks if isinstance(t, Position | Line | Plane)}
            | {load.at for load in loads}
        )
        frames = {body.landmarks[e].dof for e in effectors}
        frames |= {t.dof for t in tasks if isinstance(t, Orientation | Gaze)}
        busy = {d for f in frames for d in body.ancestors(f)}
        busy |= {d for foot in body.feet for d in body.ancestors(foot.dof)}
        self.idle = _components(body, [d.name for d in body.dofs if d.name not in busy])
        self.sagittal = _in_sagittal_planes(tasks)
        self.out_of_plane = [
            i
            for i, d in enumerate(body.dofs)
            if d.name in busy
            and np.linalg.norm(np.cross(body.axis(d.name), [0.0, 1.0, 0.0])) > 1e-9
        ]
        self.trunk_twist = lateral(body)
        self.trunk, self.flexion_sign = _trunk_pitch(body)
        self._ahead = _ahead_function(body, tuple(effectors), self.trunk)
        self.hands = tuple(
            sided_pairs(t.effector for t in tasks if isinstance(t, Position | Line | Plane))
        )
        self._crossing = _crossing_function(body, self.hands)
        self.lower, self.upper = body.lower, body.upper
        self.range = self.upper - self.lower
        self.near, self.at = _value("near_limit"), _value("at_limit")

    def check(self, q: np.ndarray, label: str, time_s: float | None = None) -> PostureCheck:
        """The report of posture ``q`` [rad], with its flags."""
        body, q = self.body, np.asarray(q, dtype=float)
        fraction = np.minimum(q - self.lower, self.upper - q) / self.range
        lower = q - self.lower < self.upper - q
        near = tuple(
            NearLimit(
                d.name,
                math.degrees(q[i]),
                math.degrees(self.lower[i] if lower[i] else self.upper[i]),
                "lower" if lower[i] else "upper",
                100.0 * float(fraction[i]),
            )
            for i, d in enumerate(body.dofs)
            if fraction[i] <= self.near
        )
        displacement = farthest = None
        if self.neutral is not None:
            away = (q - self.neutral) / self.range
            displacement = float(np.sum(np.abs(away)))
            k = int(np.argmax(np.abs(away)))
            farthest = (body.dofs[k].name, math.degrees(q[k] - self.neutral[k]))
        sym = asym_dof = None
        if self.symmetric:
            worst, asym_dof = asymmetry(body, q)
            sym = math.degrees(worst)
        plane = plane_dof = None
        if self.sagittal and self.out_of_plane:
            k = max(self.out_of_plane, key=lambda i: abs(q[i]))
            plane, plane_dof = math.degrees(abs(q[k])), body.dofs[k].name
        idle = []
        if self.neutral is not None:
            for limb, members in self.idle:
                k = max(members, key=lambda i: abs(q[i] - self.neutral[i]))
                idle.append((limb, body.dofs[k].name, math.degrees(abs(q[k] - self.neutral[k]))))
        report = PostureCheck(
            label,
            time_s,
            near,
            displacement,
            farthest,
            sym,
            asym_dof,
            plane,
            plane_dof,
            tuple(idle),
        )
        return PostureCheck(**{**report.__dict__, "flags": tuple(self._flags(q, report))})

    def _flags(self, q: np.ndarray, report: PostureCheck) -> list[str]:
        """Postures a source calls uncomfortable or extreme."""
        body, out = self.body, []
        where = f"{report.label}" + ("" if report.time_s is None else f" ({report.time_s:g} s)")
        tolerance = _value("asymmetry")
        if report.asymmetry_deg is not None and report.asymmetry_deg > tolerance:
            out.append(
                f"{where}: a mirror-symmetric task held asymmetrically ({report.asymmetric_dof} "
                f"{report.asymmetry_deg:.1f}° from its mirror, > {tolerance:g}°)"
            )
        if self.symmetric or self.sagittal:
            limit = _value("trunk_twist")
            for i in self.trunk_twist:
                if abs(math.degrees(q[i])) > limit:
                    out.append(
                        f"{where}: trunk twisted or bent sideways ({body.dofs[i].name} "
                        f"{math.degrees(q[i]):+.0f}°, > {limit:g}°) where the task asks for "
                        "neither (RULA/REBA score it)"
                    )
        if self._ahead is not None:
            extension = -self.flexion_sign * math.degrees(q[self.trunk])
            ahead = float(np.max(np.asarray(self._ahead(q))))
            if extension > _value("trunk_extension") and ahead >= _value("reach_ahead"):
                out.append(
                    f"{where}: the trunk leans back ({extension:.0f}° of lumbar extension) "
                    f"while a hand works {ahead:.2f} m ahead of it (REBA scores it)"
                )
        if self._crossing is not None:
            limit = _value("crossed_hands")
            crossing = np.asarray(self._crossing(q), dtype=float).ravel()
            for (right, left), metres in zip(self.hands, crossing, strict=True):
                if metres > limit:
                    out.append(
                        f"{where}: the forearms cross ({left} {metres:.2f} m to the right of "
                        f"{right} across the trunk, > {limit:g} m): the hands' targets swapped?"
                    )
        return out

    def held_at_limits(self, time_s: np.ndarray, q: np.ndarray) -> list[dict[str, Any]]:
        """Per DOF that rests on a limit (within the at-limit zone) during a run: the limit
        [deg] and the total time there [s], from the recorded postures (steps × DOFs)."""
        if not len(time_s):
            return []
        dt = np.diff(time_s, append=time_s[-1])
        out = []
        for i, d in enumerate(self.body.dofs):
            for side, bound in (("lower", self.lower[i]), ("upper", self.upper[i])):
                resting = np.abs(q[:, i] - bound) <= self.at * self.range[i]
                if resting.any():
                    out.append(
                        {
                            "dof": d.name,
                            "limit_deg": math.degrees(bound),
                            "side": side,
                            "seconds": float(dt[resting].sum()),
                        }
                    )
        return out

    def held_flags(self, held: list[dict[str, Any]]) -> list[str]:
        """A flag per DOF resting on a limit for at least the shipped time, on a 3-D body.
        A planar arm is left unflagged (its times are reported): it has no other joint to
        take the load, and its limit postures are the paper's own results."""
        if self.body.planar:
            return []
        most = _value("held_at_limit")
        return [
            f"{h['dof']} rests on its {h['limit_deg']:g}° limit for {h['seconds']:.0f} s "
            f"(≥ {most:g} s: a posture held at the end of a joint's range)"
            for h in held
            if h["seconds"] >= most
        ]


@lru_cache(maxsize=32)
def _ahead_function(
    body: BodyModel, effectors: tuple[str, ...], trunk: int | None
) -> ca.Function | None:
    """``ahead(q)``: how far [m] each effector lies ahead (x) of the trunk's flexion joint,
    built once per body and effectors; None without a trunk or effectors."""
    if trunk is None or not effectors:
        return None
    dof = body.dofs[trunk]
    centre = body.point(dof.name, dof.origin)
    ahead = [body.landmark(e)[0] - centre[0] for e in effectors]
    return ca.Function("ahead", [body.q], [ca.horzcat(*ahead)])


@lru_cache(maxsize=32)
def _crossing_function(body: BodyModel, hands: tuple[tuple[str, str], ...]) -> ca.Function | None:
    """``crossing(q)``: per (right, left) pair of effectors, how far [m] the left one lies to
    the right of the right one along the body's left: the y axis of the frame of the last
    DOF that moves both (the trunk both arms hang from; the world's y for a body without
    one), built once per body and pairs; None without pairs."""
    if not hands:
        return None
    crossing = []
    for right, left in hands:
        chains = (body.ancestors(body.landmarks[e].dof) for e in (right, left))
        shared = [a for a, b in zip(*chains, strict=False) if a == b]
        frame = None if not shared else shared[-1]
        leftward = body.rotation(frame) @ ca.DM([0.0, 1.0, 0.0])
        crossing.append(ca.dot(body.landmark(right) - body.landmark(left), leftward))
    return ca.Function("crossing", [body.q], [ca.horzcat(*crossing)])


def _trunk_pitch(body: BodyModel) -> tuple[int | None, float]:
    """The trunk's flexion DOF — the first unpaired DOF turning about y (sideways) whose
    subtree carries both sides — and the sign of y along its axis (+1: a positive angle
    bends forward); (None, 1) for a body without one."""
    y = np.array([0.0, 1.0, 0.0])
    for i, d in enumerate(body.dofs):
        if d.name.endswith(("_r", "_l")):
            continue
        axis = body.axis(d.name)
        if np.linalg.norm(np.cross(axis, y)) > 1e-9:
            continue
        below = [e.name for e in body.dofs if d.name in body.ancestors(e.name)]
        if any(n.endswith("_r") for n in below) and any(n.endswith("_l") for n in below):
            return i, float(np.sign(axis @ y))
    return None, 1.0


def _components(body: BodyModel, names: list[str]) -> list[tuple[str, list[int]]]:
    """The idle limbs: idle DOFs connected in the tree that branch off the trunk (the top
    one's parent is an unpaired DOF, or the world), each named by its top DOF. Idle DOFs
    beyond a busy limb's effector (a hand past the wrist held on a line) are not a limb."""
    idle = set(names)
    limbs: dict[str, list[int]] = {}
    for name in names:
        top = next(d for d in body.ancestors(name) if d in idle)
        parent = body.dofs[body.index[top]].parent
        if parent is None or not parent.endswith(("_r", "_l")):
            limbs.setdefault(top, []).append(body.index[name])
    return [(f"{top} and below", members) for top, members in limbs.items()]


def _in_sagittal_planes(tasks: Sequence[Task]) -> bool:
    """Whether the task keeps its effectors in sagittal planes: a line with no sideways
    component, or a plane whose normal points sideways."""
    y = np.array([0.0, 1.0, 0.0])
    lines = [t for t in tasks if isinstance(t, Line)]
    planes = [t for t in tasks if isinstance(t, Plane)]
    if not lines and not planes:
        return False
    flat = all(abs(np.asarray(t.direction) @ y) < 1e-9 for t in lines)
    sideways = all(
        np.linalg.norm(np.cross(np.asarray(t.normal, dtype=float), y)) < 1e-9 for t in planes
    )
    return flat and sideways
