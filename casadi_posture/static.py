"""Static answers at one posture: the torques, each half-joint's load and endurance, by
the rule the simulation follows (feasibility, and one rule for "unlimited"), at the
problem's own posture or at the one the IK solves for.

- A group that carries nothing (the antagonist of the one holding the load) never tires.
- A load above 100 %MVC exceeds the group's strength: the posture cannot be held at all,
  so the endurance is 0 and the group is "over strength".
- Otherwise the endurance is the fatigue model's time from rest to exhaustion at that
  constant load, ``inf`` where the model accumulates no fatigue (below ``T_0`` for
  ``threshold``, below the sustainable load for ``3cc_r``): the time the simulation of
  the same constant load would take to reach a fatigue level of 1.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from casadi_posture.biomech.capability import (
    Capability,
    PopulationStrength,
    capability,
    population,
)
from casadi_posture.biomech.comfort import neutral_posture
from casadi_posture.biomech.low_back import LowBack, low_back_model
from casadi_posture.biomech.low_back import limits as compression_limits
from casadi_posture.biomech.torques import Torques, footing_function
from casadi_posture.body.loads import pack
from casadi_posture.body.support import margin, support_polygon
from casadi_posture.ergonomics.plausibility import Plausibility, PostureCheck
from casadi_posture.ergonomics.posture_scores import (
    Assumptions,
    SideScores,
    body_kind,
    score_posture,
)
from casadi_posture.errors import ProblemError
from casadi_posture.frames import frame
from casadi_posture.ik.result import ACHIEVED_TOLERANCE, IKResult
from casadi_posture.ik.solvers import cached_solver
from casadi_posture.ik.tasks import Comfort
from casadi_posture.problem import Problem

#: A load above this exceeds the group's maximum voluntary torque [%MVC].
STRENGTH_PCT_MVC = 100.0
#: What every static answer says of a problem with a work–rest ``[schedule]``.
SCHEDULE_NOTE = (
    "the endurance here is a continuous hold's: the [schedule]'s rests are not in it "
    "(simulate runs them; whatif --vary schedule.t_off_s=... and duty-cycle compare them)"
)

Verdict = Literal["carries nothing", "unlimited", "limited", "over strength"]


@dataclass(frozen=True)
class GroupLoad:
    """One half-joint at one posture: strength and torque [N·m], load [%MVC], endurance [s]
    (``inf`` unlimited, 0 over strength) and the verdict that explains the endurance."""

    name: str
    dof: str
    strength: float
    torque: float
    load_pct_mvc: float
    endurance_s: float
    verdict: Verdict

    @property
    def endurance_min(self) -> float:
        return self.endurance_s / 60.0

    @property
    def over_strength(self) -> bool:
        return self.verdict == "over strength"


def endurances(problem: Problem, loads_pct_mvc: ArrayLike) -> list[tuple[float, Verdict]]:
    """Endurance [s] of every half-joint under its constant load [%MVC], and its verdict.

    The fatigue model is asked once per joint region, for all its groups' loads: the 3CC's
    time to failure is found by time stepping, and the 29-DOF body's 58 groups asked one by
    one took 4 s of a summary."""
    loads = np.asarray(loads_pct_mvc, dtype=float)
    seconds = np.where(loads == 0.0, math.inf, 0.0)
    regions = np.array([half.region for half in problem.body.half_joints])
    timed = (loads != 0.0) & (loads <= STRENGTH_PCT_MVC)
    for region in np.unique(regions[timed]):
        at = timed & (regions == region)
        seconds[at] = problem.fatigue.endurance_time_s(loads[at], str(region))
    return [
        (float(s), verdict(float(s), float(load))) for s, load in zip(seconds, loads, strict=True)
    ]


def verdict(seconds: float, load_pct_mvc: float) -> Verdict:
    """Why an endurance [s] under a load [%MVC] is what it is."""
    if load_pct_mvc == 0.0:
        return "carries nothing"
    if load_pct_mvc > STRENGTH_PCT_MVC:
        return "over strength"
    return "unlimited" if math.isinf(seconds) else "limited"


def group_loads(problem: Problem, torques: Torques) -> list[GroupLoad]:
    """Every half-joint's load and endurance at the posture of ``torques``."""
    loads = torques.load_pct_mvc
    timed = endurances(problem, loads)
    return [
        GroupLoad(
            half.name,
            half.dof,
            float(torques.strength[k]),
            float(torques.half_joint_torque[k]),
            float(loads[k]),
            *timed[k],
        )
        for k, half in enumerate(problem.body.half_joints)
    ]


def limiting(groups: Sequence[GroupLoad]) -> GroupLoad | None:
    """The group with the shortest endurance (the highest load on a tie); None when no group
    ever tires."""
    finite = [g for g in groups if math.isfinite(g.endurance_s)]
    if not finite:
        return None
    return min(finite, key=lambda g: limiting_key(g.endurance_s, g.load_pct_mvc))


def limiting_key(endurance: float, load_pct_mvc: float) -> tuple[float, float]:
    """The order of groups by which limits first: the shorter endurance, then the higher
    load, each ``tied``."""
    return tied(endurance), -tied(load_pct_mvc)


def tied(value: float) -> float:
    """``value`` to 9 significant digits: the two sides of a symmetric task, equal but for
    round-off, tie, and the first in body order (the right) is named."""
    return float(f"{value:.9g}")


def law(problem: Problem) -> str:
    """The recovery law and its parameters, in one line."""
    settings = problem.fatigue.settings()
    parts = [str(settings["recovery_law"])]
    if "load_threshold_pct_mvc" in settings:
        parts.append(f"T_0 = {settings['load_threshold_pct_mvc']:g} %MVC")
    rates = ", ".join(f"{k} {v:g}" for k, v in settings["recovery_rate_per_s"].items())
    parts.append(f"R = {rates} 1/s (×{settings['rest_multiplier']:g} when unloaded)")
    if "fatigue_rate_per_s" in settings:
        fatigue = ", ".join(f"{k} {v:g}" for k, v in settings["fatigue_rate_per_s"].items())
        parts.append(f"F = {fatigue} 1/s")
    return "; ".join(parts)


def rule(problem: Problem) -> str:
    """The rule behind every endurance of this problem, in one line."""
    return f"{problem.fatigue.rule()}; 0 above {STRENGTH_PCT_MVC:g} %MVC (over strength)"


@dataclass(frozen=True)
class Level:
    """A priority level's outcome: its tasks, residual [``unit``], whether it was achieved
    (residual at most ``ACHIEVED_TOLERANCE``) and whether it is the ``criterion`` (the last
    level of comfort or joint-reference tasks: minimised, never expected to reach zero)."""

    level: int
    tasks: str
    residual: float
    unit: str
    achieved: bool
    criterion: bool = False

    @property
    def outcome(self) -> str:
        """In a word or three: ``level_outcome``."""
        return level_outcome(self.achieved, self.criterion)


def level_outcome(achieved: bool, criterion: bool) -> str:
    """A level's outcome in a word or three: yes, NO, or minimised (a criterion level, never
    expected to reach zero)."""
    if criterion and not achieved:
        return "minimised (criterion)"
    return "yes" if achieved else "NO"


@dataclass(frozen=True)
class StaticAnswer:
    """Torques, loads and endurances at one posture: the problem's own (``at_posture``)
    or the one the IK solves for (``solve``, which sets ``ik`` and ``levels``), and the
    share of men and women able to exert its torques (``capable``, biomech/capability.py).
    ``flags`` say, one line each, why the answer cannot be used as it is (empty: it can);
    ``plausibility`` reports how plausible the posture is for a person (its flags are
    among ``flags``); ``scores`` its RULA and REBA per side (none for a body they do not
    fit: ``posture_scores``); ``low_back`` the compression and shear at L5/S1 (None
    for a body without a lumbar joint: ``low_back``)."""

    problem: Problem
    torques: Torques
    groups: tuple[GroupLoad, ...]
    ik: IKResult | None
    levels: tuple[Level, ...]
    flags: tuple[str, ...]
    capable: Capability
    plausibility: PostureCheck | None = None
    scores: tuple[SideScores, ...] = ()
    low_back: LowBack | None = None

    def __repr__(self) -> str:
        group = self.limiting
        limiting = "none" if group is None else f"{group.name} at {group.load_pct_mvc:.1f} %MVC"
        return (
            f"StaticAnswer({str(self.problem.path)!r}, reached={self.reached}, "
            f"limiting={limiting}, flags={self.flags})"
        )

    @property
    def posture_deg(self) -> dict[str, float]:
        """The posture, per DOF [deg]."""
        return {
            d: math.degrees(float(a))
            for d, a in zip(self.problem.body.dof_names, self.torques.q, strict=True)
        }

    @property
    def reached(self) -> bool | None:
        """Whether level 1 was achieved (None: nothing was solved)."""
        return self.levels[0].achieved if self.levels else None

    @property
    def feasible(self) -> bool:
        """No group needs more than its strength."""
        return not any(g.over_strength for g in self.groups)

    @property
    def limiting(self) -> GroupLoad | None:
        """The group with the shortest endurance (None: no group tires)."""
        return limiting(self.groups)

    @property
    def rule(self) -> str:
        """The rule behind every endurance (``rule``)."""
        return rule(self.problem)

    def dofs(self) -> list[dict[str, float | str]]:
        """Per DOF its angle [deg] and external, passive and active torque [N·m]."""
        t = self.torques
        return [
            {
                "name": d,
                "angle_deg": math.degrees(float(t.q[i])),
                "external_Nm": float(t.external[i]),
                "passive_Nm": float(t.passive[i]),
                "active_Nm": float(t.active[i]),
            }
            for i, d in enumerate(self.problem.body.dof_names)
        ]

    def half_joints(self) -> list[dict[str, float | str | None]]:
        """Per half-joint its strength and torque [N·m], load [%MVC], endurance [min] (None:
        unlimited; the verdict says why) and verdict."""
        return [
            {
                "name": g.name,
                "dof": g.dof,
                "strength_Nm": g.strength,
                "torque_Nm": g.torque,
                "load_pct_mvc": g.load_pct_mvc,
                "endurance_min": g.endurance_min if math.isfinite(g.endurance_min) else None,
                "verdict": g.verdict,
            }
            for g in self.groups
        ]

    def capable_groups(self) -> list[dict[str, float | str]]:
        """Per half-joint the share of men and of women able to exert its torque [%], the
        population mean and SD of each sex [N·m], where the means come from, and the SD's
        source and status (``measured``: a study's SD; ``estimate``: our CV)."""
        return [
            {
                "name": c.name,
                "torque_Nm": c.required,
                "capable_male_pct": c.capable_pct["male"],
                "capable_female_pct": c.capable_pct["female"],
                "mean_male_Nm": c.population.mean["male"],
                "mean_female_Nm": c.population.mean["female"],
                "sd_male_Nm": c.population.sd["male"],
                "sd_female_Nm": c.population.sd["female"],
                "mean_source": c.population.source,
                "sd_status": c.population.sd_status,
                "sd_source": c.population.sd_source,
            }
            for c in self.capable.groups
        ]

    def capable_report(self) -> dict[str, object]:
        """The share of men and of women capable of the task [%] with its weakest group and
        the design limit, the notes, which SDs are estimates, and ``capable_groups``."""
        return {
            **self.capable.to_dict(),
            "notes": self.capable.notes(),
            "sd_note": self.capable.sd_line(),
            "half_joints": self.capable_groups(),
        }

    def to_frame(self) -> object:
        """The half-joints as a pandas DataFrame (needs pandas)."""
        return frame(self.half_joints())

    def capable_frame(self) -> object:
        """``capable_groups`` as a pandas DataFrame (needs pandas)."""
        return frame(self.capable_groups())

    def dofs_frame(self) -> object:
        """The DOFs' torques as a pandas DataFrame (needs pandas)."""
        return frame(self.dofs())

    def levels_frame(self) -> object:
        """The priority levels as a pandas DataFrame (needs pandas)."""
        return frame([level.__dict__ for level in self.levels])


def at_posture(problem: Problem, q: Sequence[float] | None = None) -> StaticAnswer:
    """Torques and loads at ``q`` [rad] (default: the problem's ``posture_deg``)."""
    torques = problem.torque_model().evaluate(problem.posture if q is None else q)
    groups = tuple(group_loads(problem, torques))
    capable = capable_shares(problem, torques)
    check = plausibility(problem).check(torques.q, "posture")
    back = low_back(problem, torques.q)
    flags = (
        *_over_strength(groups),
        *compression_flags(None if back is None else back.compression),
        *_off_balance(problem, torques.q),
        *check.flags,
    )
    scores = posture_scores(problem, torques.q)
    return StaticAnswer(problem, torques, groups, None, (), flags, capable, check, scores, back)


def capable_shares(problem: Problem, torques: Torques) -> Capability:
    """The share of each sex strong enough for every group's torque at ``torques``."""
    return capability(population_strength(problem, torques.strength), torques.half_joint_torque)


def solve(problem: Problem, solver: str | None = None) -> StaticAnswer:
    """Solve the prioritized IK from the problem's posture with ``solver`` (default: the
    file's) and answer at the solution; a problem without tasks is answered where it is."""
    if not problem.tasks:
        return at_posture(problem)
    hierarchy = problem.hierarchy()
    name = solver or problem.spec.solver.name
    result = cached_solver(name, hierarchy, problem.spec.solver).solve(problem.posture)
    answer = at_posture(problem, result.q)
    criterion = hierarchy.criterion_level()
    levels = tuple(
        Level(k + 1, tasks, float(result.residuals[k]), unit, result.achieved[k], k == criterion)
        for k, (tasks, unit) in enumerate(
            zip(hierarchy.level_names(), hierarchy.level_units(), strict=True)
        )
    )
    flags = [] if result.success else [f"the {name} solver failed: {result.status}"]
    top = levels[0]
    if not top.achieved:
        flags.append(
            f"level 1 ({top.tasks}) not achieved: residual {top.residual:.3g} {top.unit} > "
            f"{ACHIEVED_TOLERANCE:g} {top.unit}; the task is out of the body's reach or "
            "blocked by a joint limit (positions are in metres)"
        )
    for level in levels[1:]:
        if not level.achieved and not level.criterion:
            flags.append(
                f"level {level.level} ({level.tasks}) not achieved: residual "
                f"{level.residual:.3g} {level.unit} > {ACHIEVED_TOLERANCE:g} {level.unit}; "
                "the answer is for the nearest posture the body reaches, not the task as given"
            )
    return StaticAnswer(
        problem,
        answer.torques,
        answer.groups,
        result,
        levels,
        (*flags, *answer.flags),
        answer.capable,
        answer.plausibility,
        answer.scores,
        answer.low_back,
    )


def _over_strength(groups: Sequence[GroupLoad]) -> list[str]:
    over = [g for g in groups if g.over_strength]
    if not over:
        return []
    needs = ", ".join(f"{g.name} needs {g.load_pct_mvc:.2f} %MVC" for g in over)
    return [f"over strength: {needs}; this posture cannot be held"]


def compression_flags(compression: float | None, detail: str = "") -> list[str]:
    """A flag when the L5/S1 compression [N] is above the NIOSH design limit, naming the
    limit it is above (the upper one above 6400 N); ``detail`` follows the number (a
    run's times). None: not computed, no flag."""
    limit = compression_limits()
    if compression is None or compression <= limit["design"]:
        return []
    if compression > limit["upper"]:
        above = f"the NIOSH upper limit of {limit['upper']:g} N: hazardous to nearly all workers"
    else:
        above = f"the NIOSH design limit of {limit['design']:g} N: the task should be redesigned"
    return [
        f"low-back compression {compression:.0f} N at L5/S1{detail} is above {above} "
        "(Chaffin & Andersson's single equivalent muscle; docs/low_back.md)"
    ]


def _off_balance(problem: Problem, q: Sequence[float]) -> list[str]:
    """A flag when a body standing on two feet has the centre of pressure of its weight
    and loads (pushes included) outside the support polygon of its feet, or a foot's share
    of the floor's reaction below 0 (body/support.py): the floor would have to pull."""
    body = problem.body
    footing = footing_function(body, tuple(load.at for load in problem.loads))
    if footing is None:
        return []
    pressure, share = (np.asarray(v).ravel() for v in footing(q, pack(problem.loads)))
    distance = margin(support_polygon(body, q), pressure)
    carried, root = (
        next(f.name for f in body.feet if (f.dof is None) == rooted) for rooted in (False, True)
    )
    shares = {carried: float(share[0]), root: 1.0 - float(share[0])}
    pulled = [f"{name} {value:.3f}" for name, value in shares.items() if value < 0]
    if distance < 0:
        return [
            "off balance: the centre of pressure of the body's weight and the loads lies "
            f"{100 * -distance:.1f} cm outside the feet's support polygon; the person cannot "
            "stand like this without holding on"
        ]
    if pulled:
        return [
            "the centre of pressure lies beyond a sole's centre, where the rule sharing the "
            f"floor's reaction gives a foot a negative share ({', '.join(pulled)}): the leg "
            "torques assume the floor pulls that foot down, outside the rule's validity"
        ]
    return []


def plausibility(problem: Problem) -> Plausibility:
    """The plausibility checks of ``problem``'s body, tasks and loads, the neutral posture
    its comfort level uses (else the shipped one; none for a body without one)."""
    tasks = problem.task_objects()
    comfort = next((t for t in tasks if isinstance(t, Comfort)), None)
    if comfort is not None:
        neutral = comfort.measure.neutral
    else:
        try:
            neutral = neutral_posture(problem.body)
        except ProblemError:
            neutral = None
    return Plausibility(problem.body, tasks, problem.loads, neutral)


def posture_scores(
    problem: Problem, q: Sequence[float], held: Sequence[float] | None = None
) -> tuple[SideScores, ...]:
    """RULA and REBA per side of ``problem``'s body at ``q`` [rad] holding its loads (those
    ``held`` marks 1, one mark per load; None: all), with the file's ``[ergonomics]``
    inputs; empty for a body the worksheets do not fit (ergonomics/posture_scores.py)."""
    if body_kind(problem.body) is None:
        return ()
    loads = (
        problem.loads
        if held is None
        else [load for load, on in zip(problem.loads, held, strict=True) if on]
    )
    return tuple(score_posture(problem.body, q, loads, Assumptions.of(problem.spec.ergonomics)))


def low_back(problem: Problem, q: Sequence[float]) -> LowBack | None:
    """The compression and shear [N] at L5/S1 of ``problem``'s body at ``q`` [rad] holding
    its loads (biomech/low_back.py); None for a body without a lumbar joint (not computed,
    never zero)."""
    model = low_back_model(problem.body, problem.loads)
    return None if model is None else model.evaluate(q)


#: The keys that set a group's strength outright (strength_scale scales the default).
ABSOLUTE_STRENGTH_KEYS = ("strength_Nm", "strength_curve", "strength_ratio")


def population_strength(
    problem: Problem, strength: Sequence[float]
) -> tuple[PopulationStrength, ...]:
    """The population strength of every half-joint of ``problem`` (``body.half_joints`` order)
    at its body's stature, mass and age; ``strength`` [N·m] the problem's own at the posture
    considered, the mean of a group whose strength the file sets."""
    absolute = {
        name
        for name, group in _file_groups(problem).items()
        if any(getattr(group, k) is not None for k in ABSOLUTE_STRENGTH_KEYS)
    }
    own = {
        p.name.removeprefix("strength."): p.source
        for p in problem.parameters
        if p.name.removeprefix("strength.") in absolute
    }
    groups = [h.name for h in problem.body.half_joints]
    return population(problem.spec.body, groups, own, strength)


def _file_groups(problem: Problem) -> dict[str, Any]:
    """The muscle groups the problem file describes, by name (``body.half_joints`` or the
    sides of ``body.tree``'s DOFs)."""
    body = problem.spec.body
    if body.tree is None:
        return dict(body.half_joints)
    return {g.name: g for dof in body.tree.dofs for g in (dof.positive, dof.negative)}
