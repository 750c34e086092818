"""Sensitivities of the start loads and static endurances to every numeric input of a problem
(docs/sensitivity.md): what matters most for how long a task can be held.

At the posture the IK solves for (``static.solve``), each half-joint's load [%MVC], each
limited group's static endurance [s] and the task's (its limiting group's) are expressions of
the posture and the inputs (``ParametricProblem``); their total derivatives add the
posture's own change (``posture_derivative``). One compiled call gives every value and
partial derivative. Elasticities ``(dy/dx)·x/y`` make inputs of different units comparable:
the % change of the outcome per % change of the input.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from casadi_posture.biomech.low_back import MODEL
from casadi_posture.problem import Problem
from casadi_posture.sensitivity_analysis.parametric import Input, ParametricProblem
from casadi_posture.sensitivity_analysis.posture import PostureDerivative, posture_derivative
from casadi_posture.static import StaticAnswer, low_back
from casadi_posture.static import solve as solve_static

#: The parametric graph must reproduce the problem's own torques to this [N·m].
CONSISTENCY = 1e-8
#: Polishing a converged IK answer moves it by 1e-8 rad at most and leaves its optimality
#: conditions at 1e-14 (the shipped problems); one that moves further [rad] or stays further
#: off was not a solution, and the derivatives there are not the answer's.
POLISHED_RAD = 1e-4
POLISHED_STATIONARITY = 1e-6


@dataclass(frozen=True)
class Sensitivity:
    """Outcomes at the solved posture and their derivatives with respect to ``inputs``.

    ``load_pct_mvc`` per half-joint and ``d_load`` [%MVC per input unit] (half-joints ×
    inputs); ``endurance_s`` and ``d_endurance`` [s per input unit] with ``limited`` marking
    the groups that have one (the others carry nothing, hold it indefinitely or exceed their
    strength: their rows are zero and not reported); ``task_endurance_s`` the limiting
    group's (None: no group tires, or the answer is flagged) and ``d_task``. ``posture``
    holds dq/dθ (None: the tasks leave the posture free; then the derivatives hold the
    posture fixed and ``flags`` say so). ``compression`` is the compression [N] at L5/S1 and
    ``d_compression`` its derivative [N per input unit] (None: no lumbar joint)."""

    answer: StaticAnswer
    inputs: tuple[Input, ...]
    left_out: dict[str, str]
    groups: tuple[str, ...]
    load_pct_mvc: np.ndarray
    d_load: np.ndarray
    limited: np.ndarray
    endurance_s: np.ndarray
    d_endurance: np.ndarray
    limiting: str | None
    task_endurance_s: float | None
    d_task: np.ndarray
    posture: PostureDerivative
    flags: tuple[str, ...]
    wall_time_s: float
    compression: float | None = None
    d_compression: np.ndarray | None = None

    def elasticity(self, derivative: np.ndarray, outcome: float) -> list[float | None]:
        """``derivative·x/outcome`` per input (None where the input or the outcome is 0)."""
        out: list[float | None] = []
        for d, item in zip(derivative, self.inputs, strict=True):
            ok = item.value != 0.0 and outcome != 0.0
            out.append(float(d * item.value / outcome) if ok else None)
        return out

    def ranked(self, kinds: Sequence[str] = ()) -> list[dict[str, object]]:
        """Every input (of ``kinds``, default all) with the task's endurance derivative
        [min per unit] and elasticity, and the limiting group's load derivative and
        elasticity, ranked by the endurance's elasticity (largest magnitude first; inputs at
        0 last, by their derivative)."""
        if self.task_endurance_s is None:
            return []
        k = self.groups.index(self.limiting)
        e_task = self.elasticity(self.d_task, self.task_endurance_s)
        e_load = self.elasticity(self.d_load[k], float(self.load_pct_mvc[k]))
        rows = [
            {
                "key": item.key,
                "kind": item.kind,
                "value": item.value,
                "unit": item.unit,
                "d_endurance_min_per_unit": float(self.d_task[j]) / 60.0,
                "endurance_elasticity": e_task[j],
                "d_load_pct_mvc_per_unit": float(self.d_load[k, j]),
                "load_elasticity": e_load[j],
            }
            for j, item in enumerate(self.inputs)
            if not kinds or item.kind in kinds
        ]
        return _by_elasticity(rows, "endurance_elasticity", "d_endurance_min_per_unit")

    def ranked_compression(self, kinds: Sequence[str] = ()) -> list[dict[str, object]]:
        """Every input (of ``kinds``, default all) with the L5/S1 compression's derivative [N
        per unit] and elasticity, ranked as ``ranked`` (none without a lumbar joint)."""
        if self.compression is None or self.d_compression is None:
            return []
        elasticity = self.elasticity(self.d_compression, self.compression)
        rows = [
            {
                "key": item.key,
                "kind": item.kind,
                "value": item.value,
                "unit": item.unit,
                "d_compression_N_per_unit": float(self.d_compression[j]),
                "compression_elasticity": elasticity[j],
            }
            for j, item in enumerate(self.inputs)
            if not kinds or item.kind in kinds
        ]
        return _by_elasticity(rows, "compression_elasticity", "d_compression_N_per_unit")

    def to_dict(self) -> dict[str, object]:
        """Everything, for JSON: inputs, outcomes, every derivative and elasticity, the
        problem's notes (spec/slips.py)."""
        groups = []
        for k, name in enumerate(self.groups):
            limited = bool(self.limited[k])
            load = float(self.load_pct_mvc[k])
            endurance = float(self.endurance_s[k]) if limited else None
            groups.append(
                {
                    "name": name,
                    "load_pct_mvc": load,
                    "d_load_pct_mvc": _by_key(self.inputs, self.d_load[k]),
                    "load_elasticity": _by_key(self.inputs, self.elasticity(self.d_load[k], load)),
                    "endurance_min": None if endurance is None else endurance / 60.0,
                    "d_endurance_min": _by_key(self.inputs, self.d_endurance[k] / 60.0)
                    if limited
                    else None,
                    "endurance_elasticity": _by_key(
                        self.inputs, self.elasticity(self.d_endurance[k], endurance)
                    )
                    if limited
                    else None,
                }
            )
        posture = self.posture
        return {
            "problem": str(self.answer.problem.path),
            "inputs": [item.__dict__ for item in self.inputs],
            "left_out": self.left_out,
            "posture_deg": self.answer.posture_deg,
            "posture": {
                "determined": posture.dq is not None,
                "kept_levels": list(posture.kept),
                "minimised_level": posture.minimised,
                "held_at_limits": list(posture.held),
                "stationarity": posture.stationarity,
                "note": posture.note,
            },
            "task": {
                "limiting": self.limiting,
                "endurance_min": None
                if self.task_endurance_s is None
                else self.task_endurance_s / 60.0,
                "ranked": self.ranked(),
            },
            "groups": groups,
            "low_back": {
                "model": MODEL,
                "compression_N": self.compression,
                "ranked": self.ranked_compression(),
                "note": None
                if self.compression is not None
                else "not computed (the body has no lumbar joint)",
            },
            "notes": list(self.answer.problem.notes),
            "flags": list(self.flags),
            "wall_time_s": self.wall_time_s,
        }


def sensitivity(problem: Problem, solver: str | None = None) -> Sensitivity:
    """Solve ``problem``'s IK as ``solve`` does and differentiate its outcomes with respect to
    every numeric input (the posture's change included, by the implicit function theorem)."""
    start = time.perf_counter()
    answer = solve_static(problem, solver)
    hierarchy = problem.hierarchy() if problem.tasks else None
    graph = ParametricProblem(problem, hierarchy)
    flags = list(answer.flags)
    if hierarchy is None:
        posture = PostureDerivative(
            answer.torques.q, np.zeros((problem.body.n, 0)), (), (), None, 0.0
        )
        dq = np.zeros((problem.body.n, graph.values.size))
    else:
        with np.errstate(over="ignore", invalid="ignore"):  # a Newton step off to infinity
            polished = posture_derivative(
                graph, answer.torques.q, [lv.achieved for lv in answer.levels]
            )
        posture = _of_the_answer(polished, answer.torques.q, problem)
        dq = posture.dq
        if dq is None:
            flags.append(f"derivatives hold the posture fixed: {posture.note}")
            dq = np.zeros((problem.body.n, graph.values.size))
    q = posture.q
    loads = graph.load
    limited = np.array([g.verdict == "limited" for g in answer.groups])
    endurance = [e if ok else ca.SX(0) for e, ok in zip(graph.endurance, limited, strict=True)]
    if any(e is None for e in graph.endurance):
        flags.append(
            f"the {problem.fatigue.name} law's endurance is found by time stepping: no "
            "derivatives of endurances"
        )
        limited[:] = False
        endurance = [ca.SX(0)] * loads.numel()
    back = [] if graph.compression is None else [graph.compression]
    outcomes = ca.vertcat(loads, *endurance, *back)
    function = ca.Function(
        "outcomes",
        [graph.q, graph.theta],
        [
            outcomes,
            ca.jacobian(outcomes, graph.q),
            ca.jacobian(outcomes, graph.theta),
            graph.tau_act,
        ],
    )
    value, by_q, by_theta, tau = (np.asarray(v) for v in function(q, graph.values))
    _check_consistency(problem, q, tau.ravel())
    compression = float(value[-1, 0]) if back else None
    _check_compression(problem, q, compression)
    total = by_theta + by_q @ dq
    m = loads.numel()
    groups = tuple(h.name for h in problem.body.half_joints)
    # The task's endurance has a derivative where the posture solves and can be held (an
    # implausible or off-balance posture still has one, and says so in its flags).
    held = (
        answer.feasible and (answer.ik is None or answer.ik.success) and answer.reached is not False
    )
    limiting_group = answer.limiting if held else None
    limiting = None
    task, d_task = None, np.zeros(graph.values.size)
    if limiting_group is not None and limited[groups.index(limiting_group.name)]:
        limiting = limiting_group.name
        k = groups.index(limiting)
        task, d_task = float(value[m + k, 0]), total[m + k]
        ties = [
            g.name
            for g in answer.groups
            if g.name != limiting and math.isclose(g.endurance_s, task, rel_tol=1e-6)
        ]
        if ties:
            flags.append(
                f"{limiting} ties with {', '.join(ties)}: the task's endurance has a kink "
                "there; its derivative is the limiting group's, one-sided"
            )
    return Sensitivity(
        answer,
        tuple(graph.inputs),
        dict(graph.left_out),
        groups,
        value[:m, 0],
        total[:m],
        limited,
        np.where(limited, value[m : 2 * m, 0], 0.0),
        np.where(limited[:, None], total[m : 2 * m], 0.0),
        limiting,
        task,
        d_task,
        posture,
        tuple(flags),
        time.perf_counter() - start,
        compression,
        total[-1] if back else None,
    )


def _check_consistency(problem: Problem, q: np.ndarray, tau: np.ndarray) -> None:
    """The graph's active torques equal the problem's own at ``q`` (a wrong graph fails loud)."""
    own = problem.torque_model().evaluate(q).active
    error = float(np.max(np.abs(own - tau), initial=0.0))
    if error > CONSISTENCY * max(1.0, float(np.max(np.abs(own), initial=0.0))):
        raise RuntimeError(
            f"the sensitivity graph's torques differ from the problem's by {error:g} N·m"
        )


def _of_the_answer(
    posture: PostureDerivative, q0: np.ndarray, problem: Problem
) -> PostureDerivative:
    """``posture``, or, when polishing the IK's answer ``q0`` [rad] moved it further than
    ``POLISHED_RAD`` or left its optimality conditions further off than
    ``POLISHED_STATIONARITY`` (a solver that stopped short of a solution), the answer's own
    posture held fixed, its note saying why."""
    moved = np.abs(posture.q - q0)
    if not np.all(np.isfinite(moved)) or moved.max(initial=0.0) > POLISHED_RAD:
        k = int(np.argmax(np.where(np.isfinite(moved), moved, np.inf)))
        why = f"polishing it moved {problem.body.dof_names[k]} by {math.degrees(moved[k]):.3g}°"
    elif posture.stationarity > POLISHED_STATIONARITY:  # nan: not polished, the note says why
        why = f"its optimality conditions are off by {posture.stationarity:.3g}"
    else:
        return posture
    note = f"the IK's answer is not a solution ({why})"
    return PostureDerivative(q0, None, posture.held, posture.kept, None, math.nan, note)


def _check_compression(problem: Problem, q: np.ndarray, compression: float | None) -> None:
    """The graph's L5/S1 compression equals the problem's own at ``q`` (a wrong graph fails
    loud)."""
    back = low_back(problem, q)
    own = None if back is None else back.compression
    if (own is None) != (compression is None) or (
        own is not None and abs(own - compression) > CONSISTENCY * max(1.0, abs(own))
    ):
        raise RuntimeError(
            f"the sensitivity graph's compression {compression} N differs from {own} N"
        )


def _by_key(inputs: tuple[Input, ...], values: object) -> dict[str, float | None]:
    return {
        item.key: None if v is None else float(v) for item, v in zip(inputs, values, strict=True)
    }


def _by_elasticity(
    rows: list[dict[str, object]], elasticity: str, derivative: str
) -> list[dict[str, object]]:
    """``rows`` by the size of their ``elasticity``, largest first; rows without one (an
    input at 0) last, by the size of their ``derivative`` per unit."""
    return sorted(
        rows,
        key=lambda r: (r[elasticity] is None, -abs(r[elasticity] or r[derivative])),
    )
