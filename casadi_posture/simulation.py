"""Time simulation: hold the tasks, tire, shift to a less tiring posture, recover (SPEC §7).

Per step of simulated time: solve the IK from the last posture with the current
fatigue constraint; evaluate the torques; update every half-joint's fatigue over
the step at the new posture's load; apply the hysteresis; build the constraint for
the next step. Every CasADi object is built once, before the loop.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from .endurance import endurance_model
from .errors import ProblemError
from .fatigue import fatigue_model
from .fatigue_constraint import ConstraintSettings, Event, FatigueConstraint
from .problem import Problem
from .solvers import make_solver
from .tasks import Line, Task

#: The top task counts as held while its residual stays below this [m or rad].
HOLD_TOLERANCE = 1e-4


@dataclass(frozen=True)
class Timeline:
    """One row per step: time [s], q [rad], effector [m], torques [N·m] per DOF; load [%MVC],
    fatigue level and hysteresis state per half-joint; the constraint owner (-1: none), the
    goal angle [rad] and Table 1 case; the residual of each priority level."""

    time: np.ndarray
    q: np.ndarray
    effector: np.ndarray
    along_line: np.ndarray | None
    external: np.ndarray
    passive: np.ndarray
    active: np.ndarray
    load: np.ndarray
    fatigue: np.ndarray
    fatigued: np.ndarray
    owner: np.ndarray
    goal: np.ndarray
    case: list[str]
    residuals: np.ndarray


@dataclass(frozen=True)
class SimulationResult:
    """A simulated hold: its tasks, the unit of each level's residual, the timeline, the
    events and solver statistics (wall times [s])."""

    problem: Problem
    solver: str
    settings: ConstraintSettings
    effector: str
    tasks: tuple[Task, ...]
    level_units: tuple[str, ...]
    timeline: Timeline
    events: list[Event]
    wall_time_s: float
    ik_time_s: float
    ik_failures: int
    ik_iterations: int


def constraint_settings(problem: Problem) -> ConstraintSettings:
    """The fatigue-constraint settings of a problem file."""
    f = problem.spec.fatigue
    return ConstraintSettings(
        fatigue_threshold=f.fatigue_threshold,
        recovery_threshold=f.recovery_threshold,
        strategy=f.strategy,
        r_min=f.r_min,
        epsilon=f.epsilon_Nm,
        beta=f.beta,
        max_step=math.radians(f.max_step_deg),
        alpha=f.alpha_rad_per_Nm2,
    )


def simulate(problem: Problem, solver: str | None = None) -> SimulationResult:
    """Simulate the problem's hold for ``simulation.duration_s`` with ``solver``
    (default: the file's); stops early when a half-joint is exhausted (fatigue 1)."""
    if not problem.tasks:
        raise ProblemError(problem.path, "tasks", [], "at least one task to hold")
    start = time.perf_counter()
    spec, body = problem.spec, problem.body
    name = solver or spec.solver.name
    hierarchy = problem.hierarchy()
    ik = make_solver(name, hierarchy, spec.solver)
    torque_model = problem.torque_model()
    regions = [h.region for h in body.half_joints]
    fatigue = fatigue_model(
        spec.fatigue.model,
        regions=regions,
        endurance=endurance_model(spec.fatigue.endurance),
        recovery_threshold_pct_mvc=spec.fatigue.load_threshold_pct_mvc,
    )
    settings = constraint_settings(problem)
    constraint = FatigueConstraint(body, problem.passive, settings)
    effector, line = _tracked(hierarchy)
    position = ca.Function("effector", [body.q], [body.landmark(effector)])

    dt = spec.simulation.time_step_s
    steps = math.floor(spec.simulation.duration_s / dt + 1e-9) + 1
    n, m, depth = body.n, 2 * body.n, hierarchy.depth
    rec = {
        "q": np.zeros((steps, n)),
        "effector": np.zeros((steps, 3)),
        "external": np.zeros((steps, n)),
        "passive": np.zeros((steps, n)),
        "active": np.zeros((steps, n)),
        "load": np.zeros((steps, m)),
        "fatigue": np.zeros((steps, m)),
        "fatigued": np.zeros((steps, m), dtype=bool),
        "owner": np.full(steps, -1),
        "goal": np.full(steps, np.nan),
        "residuals": np.zeros((steps, depth)),
    }
    cases = [""] * steps
    events: list[Event] = []
    state, q, torques = fatigue.initial_state(), problem.posture.copy(), None
    ik_time, failures, iterations, held, last = 0.0, 0, 0, True, steps
    for step in range(steps):
        now = step * dt
        planned = constraint.hyperplane(q, torques) if torques is not None else None
        inequality, goal = planned if planned is not None else (None, None)
        tic = time.perf_counter()
        result = ik.solve(q, inequality)
        ik_time += time.perf_counter() - tic
        failures += not result.success
        iterations += result.iterations
        q = result.q
        torques = torque_model.evaluate(q)
        if step > 0:
            state = fatigue.step(state, torques.load_pct_mvc, dt)
        levels = fatigue.level(state, torques.load_pct_mvc)
        events += constraint.update(levels, now)
        if held and result.residuals[0] > HOLD_TOLERANCE:
            events.append(
                Event(
                    now,
                    "task_not_held",
                    hierarchy.level_names()[0],
                    f"level-1 residual {result.residuals[0]:.3g}",
                )
            )
        held = result.residuals[0] <= HOLD_TOLERANCE
        for key, value in (
            ("q", q),
            ("effector", np.asarray(position(q)).ravel()),
            ("external", torques.external),
            ("passive", torques.passive),
            ("active", torques.active),
            ("load", torques.load_pct_mvc),
            ("fatigue", levels),
            ("fatigued", constraint.fatigued),
            ("residuals", result.residuals),
        ):
            rec[key][step] = value
        rec["owner"][step] = -1 if constraint.owner is None else constraint.owner
        if goal is not None:
            rec["goal"][step], cases[step] = goal.angle, goal.case
        if levels.max() >= 1.0:
            worst = int(np.argmax(levels))
            events.append(
                Event(
                    now,
                    "exhausted",
                    body.half_joints[worst].name,
                    "fatigue reached 1: the task can no longer be held",
                )
            )
            last = step + 1
            break
    along = None
    if line is not None:
        direction = np.asarray(line.direction) / np.linalg.norm(line.direction)
        along = (rec["effector"][:last] - np.asarray(line.point)) @ direction
    timeline = Timeline(
        np.arange(last) * dt,
        *(rec[k][:last] for k in ("q", "effector")),
        along,
        *(
            rec[k][:last]
            for k in (
                "external",
                "passive",
                "active",
                "load",
                "fatigue",
                "fatigued",
                "owner",
                "goal",
            )
        ),
        cases[:last],
        rec["residuals"][:last],
    )
    return SimulationResult(
        problem,
        name,
        settings,
        effector,
        tuple(t for level in hierarchy.levels for t in level),
        tuple(hierarchy.level_units()),
        timeline,
        events,
        time.perf_counter() - start,
        ik_time,
        failures,
        iterations,
    )


def _tracked(hierarchy) -> tuple[str, Line | None]:
    """The effector of the highest-priority task that has one, and the first line task."""
    tasks = [t for level in hierarchy.levels for t in level]
    effectors = [t.effector for t in tasks if hasattr(t, "effector")]
    line = next((t for t in tasks if isinstance(t, Line)), None)
    return (effectors[0] if effectors else next(iter(hierarchy.body.landmarks))), line
