"""Time simulation: hold the tasks, tire, shift to a less tiring posture, recover (docs/model.md).

Per step of simulated time: solve the IK from the last posture with the current
fatigue constraint (the other solver takes over a step the first fails or stalls on,
or newly leaves level 1 unachieved where the other achieves it; a step whose IK inputs did
not change, no constraint now or before, keeps the last certified posture); evaluate
the torques; update every half-joint's fatigue over the step at the new posture's load
(a load above 100 %MVC exhausts the group at once); apply the hysteresis; build the
constraint for the next step. Every CasADi object is built once, before the loop.

With a work–rest schedule (``[schedule]``) the hold alternates with rest: during a rest
step no group carries a load, the IK is not solved, every group recovers at its unloaded
rate and the hysteresis follows the fatigue levels; work resumes from the last held
posture with the constraint as it then stands.
"""

from __future__ import annotations

import math
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field, replace
from typing import Literal

import casadi as ca
import numpy as np

from casadi_posture import interrupt
from casadi_posture.adjustment.constraint import (
    Adjustment,
    ConstraintSettings,
    Event,
    FatigueConstraint,
)
from casadi_posture.adjustment.reduced_torque import Goal
from casadi_posture.adjustment.whole_body import WholeBodyAdjustment
from casadi_posture.biomech.fatigue import FatigueModel
from casadi_posture.biomech.shape import Shape, numbers, scalable
from casadi_posture.biomech.torques import TorqueModel, Torques
from casadi_posture.body.loads import LOAD_PARAMETERS
from casadi_posture.body.support import Support
from casadi_posture.body.tree import BodyModel
from casadi_posture.compiled import Compiled
from casadi_posture.data import parameters
from casadi_posture.errors import ProblemError
from casadi_posture.ik.hierarchy import Inequality, TaskHierarchy
from casadi_posture.ik.result import ACHIEVED_TOLERANCE, IKResult
from casadi_posture.ik.solvers import SOLVER_NAMES, Solver, cached_solver
from casadi_posture.ik.tasks import Comfort, Line, Task, tasks_from_specs
from casadi_posture.motion.recording import Recording
from casadi_posture.problem import Problem
from casadi_posture.spec.schema import ComfortTask
from casadi_posture.static import STRENGTH_PCT_MVC

#: What a step of the timeline was: the tasks held, or a rest with the load put down.
Phase = Literal["hold", "rest"]

#: Why a run ended: it ran its duration, a group was exhausted (or needed more than its
#: strength), the top task could not be achieved at the start, Ctrl-C, or (asked for with
#: ``stop_at_threshold``) a group reached the fatigue threshold.
Stop = Literal["completed", "exhausted", "never_held", "interrupted", "fatigue_threshold"]

#: The solver column of a frame whose posture a recording gave (``replay``).
RECORDED = "recorded"


@dataclass(frozen=True)
class Timeline:
    """One row per step: time [s], q [rad], effector [m], torques [N·m] per DOF; load [%MVC],
    fatigue level and hysteresis state per half-joint; the constraint owner (-1: none), the
    goal angle [rad] and Table 1 case; the residual of each priority level; the solver that
    gave the posture ('' on a rest step); the phase of each step (``hold`` or ``rest``);
    for a body on its feet, the centre of mass's floor projection [m] (with the held loads)
    and its margin inside the support polygon [m] (body/support.py). A rest step repeats the
    last held posture, its effector and centre of mass (the relaxed posture is not
    modelled); its loads are 0 and its torques and residuals NaN (nothing is held). ``held``:
    per step, whether each of the problem's loads is held (a replay whose recording says so;
    None: every load on every hold step)."""

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
    solver: list[str]
    phase: list[Phase]
    balance: tuple[np.ndarray, np.ndarray] | None = None
    held: np.ndarray | None = None


@dataclass(frozen=True)
class SimulationResult:
    """A simulated hold: its tasks, the name and unit of each level, the timeline, the
    events, why it stopped and solver statistics (wall times [s]); ``recording`` the motion that
    gave the postures instead of the IK (``replay``; None: simulated). ``ik_failures`` counts
    steps whose posture no solver could certify; ``ik_fallbacks`` the steps the other solver
    was called on after a failure or stall, or took over because the first left level 1
    unachieved where it achieves it; ``ik_reused`` the steps that kept the last
    certified posture because no constraint applied then or now (the targets are fixed)."""

    problem: Problem
    solver: str
    settings: ConstraintSettings
    effector: str
    tasks: tuple[Task, ...]
    level_names: tuple[str, ...]
    level_units: tuple[str, ...]
    timeline: Timeline
    events: list[Event]
    stop: Stop
    duration_s: float
    wall_time_s: float
    ik_time_s: float
    ik_failures: int
    ik_fallbacks: int
    ik_iterations: int
    ik_reused: int
    schedule: Schedule | None = None
    recording: Recording | None = None

    def __repr__(self) -> str:
        return (
            f"SimulationResult({str(self.problem.path)!r}, solver={self.solver!r}, "
            f"stop={self.stop!r}, steps={len(self.timeline.time)}, events={len(self.events)})"
        )


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
        keep_levels=f.keep_levels,
        adjustment=adjustment(problem),
        fatigue_weight=fatigue_weight(problem),
    )


def adjustment(problem: Problem) -> Adjustment:
    """The problem's fatigue adjustment: the file's, else the paper's on every body. (The
    whole-body one holds longer on the wall and seated problems but, with equal joint
    weights, turns the trunk 24-41° on the seated, drill and shelf problems: a file chooses
    it; docs/comfort.md.)"""
    return problem.spec.fatigue.adjustment or "paper"


def fatigue_weight(problem: Problem) -> float:
    """k of the whole-body adjustment's effort weights 1 + k·F: the file's, else the comfort
    measure's shipped value."""
    given = problem.spec.fatigue.fatigue_weight
    return float(parameters.value("comfort", "fatigue_weight") if given is None else given)


def _effort_comfort(problem: Problem) -> Comfort | None:
    """The problem's comfort task if it counts effort."""
    tasks = tasks_from_specs(
        [t for t in problem.spec.tasks if isinstance(t, ComfortTask)],
        problem.body,
        problem.loads,
        problem.posture,
        problem.passive,
        problem.strength,
    )
    return next((t for t in tasks if isinstance(t, Comfort) and t.measure.effort), None)


@dataclass(frozen=True)
class Schedule:
    """A work–rest schedule on the step grid of ``dt_s`` [s]: ``hold_steps`` steps of hold,
    then ``rest_steps`` of rest, repeated. Each phase is its time in the file (``t_on_s``,
    ``t_off_s``) rounded up to whole steps: ``n = ⌈t/dt⌉`` (at least one step of hold).

    Step k (at k·dt) stands for the interval ((k−1)·dt, k·dt], whose load its fatigue update
    uses; step 0 is the start, a hold. Step k ≥ 1 is a rest when
    ``(k − 1) mod (hold_steps + rest_steps) ≥ hold_steps``: every cycle holds for
    ``hold_steps·dt`` and rests for ``rest_steps·dt``."""

    t_on_s: float
    t_off_s: float
    dt_s: float
    hold_steps: int
    rest_steps: int

    @classmethod
    def of(cls, problem: Problem) -> Schedule | None:
        """The problem's ``[schedule]`` on its step grid (None: no schedule)."""
        spec, dt = problem.spec.schedule, problem.spec.simulation.time_step_s
        if spec is None:
            return None
        hold = max(1, whole_steps(spec.t_on_s, dt))
        return cls(spec.t_on_s, spec.t_off_s, dt, hold, whole_steps(spec.t_off_s, dt))

    @property
    def period_steps(self) -> int:
        """Steps of one work cycle (hold and rest)."""
        return self.hold_steps + self.rest_steps

    def resting(self, step: int) -> bool:
        """Whether step ``step`` is a rest."""
        return step > 0 and (step - 1) % self.period_steps >= self.hold_steps


def whole_steps(seconds: float, dt_s: float) -> int:
    """``⌈seconds/dt_s⌉``, the steps a phase of ``seconds`` [s] takes on the grid of ``dt_s``
    [s] (a relative 1e-9 of rounding forgiven: 0.3 s of 0.1 s steps is 3 steps)."""
    return math.ceil(seconds / dt_s - 1e-9)


class _Recorder:
    """The timeline's rows as they come: memory grows with the steps actually run."""

    def __init__(self) -> None:
        self.rows: dict[str, list] = {}

    def add(self, **values: object) -> None:
        for key, value in values.items():
            self.rows.setdefault(key, []).append(value)

    def array(self, key: str) -> np.ndarray:
        return np.asarray(self.rows[key])


class _Solvers:
    """The problem's solver and, built on first need, the other one to fall back to."""

    def __init__(self, name: str, problem: Problem, hierarchy: TaskHierarchy) -> None:
        self.primary = cached_solver(name, hierarchy, problem.spec.solver)
        self.other_name = next(n for n in SOLVER_NAMES if n != name)
        self._problem, self._hierarchy = problem, hierarchy
        self._other: Solver | None = None

    def fallback(self) -> Solver:
        if self._other is None:
            spec = self._problem.spec.solver
            self._other = cached_solver(self.other_name, self._hierarchy, spec)
        return self._other

    def named(self, name: str) -> Solver:
        """The primary solver or the other one, by its ``name``."""
        return self.primary if name == self.primary.name else self.fallback()


def simulate(
    problem: Problem, solver: str | None = None, *, stop_at_threshold: bool = False
) -> SimulationResult:
    """Simulate the problem's hold for ``simulation.duration_s`` with ``solver`` (default:
    the file's), following its work–rest ``[schedule]`` if it has one.

    Stops early when a half-joint is exhausted (fatigue 1, or a load above its strength,
    which exhausts it at once), when the top priority level cannot be achieved at the
    start (the task is never held), or on Ctrl-C (``casadi_posture.interrupt``): the
    result then holds the steps run so far and ``stop`` says why. A step whose solver
    fails, stalls or leaves level 1 unachieved is solved again by the other solver from
    the same start (``_solve_step``); the timeline records which solver gave each
    posture. With ``stop_at_threshold`` the run also ends at the first step on which a group
    reaches ``fatigue.fatigue_threshold`` (``stop == "fatigue_threshold"``), the moment the
    fatigue-reducing constraint would engage.

    The solvers and torque functions are built on the body's shape (its numbers as symbols:
    ``biomech.shape``) and kept for the next run in this thread of any person of the same
    structure — another stature, mass, age or strength — which binds them to its own
    numbers instead of building (a population's workers: 0.15 s a worker on the 29-DOF
    standing body).
    """
    if not problem.tasks:
        raise ProblemError(problem.path, "tasks", [], "at least one task to hold")
    with interrupt.deferred():
        return _run(problem, solver, stop_at_threshold)


def _run(problem: Problem, solver: str | None, stop_at_threshold: bool) -> SimulationResult:
    """Set the run up, step it until it ends, and gather its result."""
    started = time.perf_counter()
    run = _setup(problem, solver)
    state = _State(run.fatigue.initial_state(), problem.posture.copy())
    for step in range(problem.spec.simulation.steps):
        now = step * run.dt
        if interrupt.requested():
            state.events.append(Event(now, "interrupted", "", "Ctrl-C: the run stopped here"))
            state.stop = "interrupted"
            break
        if run.schedule is not None and run.schedule.resting(step):
            _rest_step(run, state, now)
            continue
        if _hold_step(run, state, step, now, stop_at_threshold):
            break
    return _result(run, state, started)


def replay(problem: Problem, recording: Recording) -> SimulationResult:
    """The problem's body driven by ``recording`` instead of the IK (``casadi-posture
    evaluate``; docs/motion.md). Per frame: the torques and loads at the recorded posture
    with the problem's loads, the fatigue over the time since the frame before, the
    hysteresis and its events. Nothing moves the posture: no fatigue constraint acts, and a
    group the model finds exhausted (fatigue 1, or a load above its strength) is an event
    while the recording goes on. With tasks, the levels' residuals say how far the recorded
    posture is from them. Ctrl-C stops it between two frames with the frames so far
    (``stop == "interrupted"``)."""
    if recording.q.shape[1] != len(problem.body.dofs):
        raise ValueError(f"{recording.q.shape[1]} angles a frame for {len(problem.body.dofs)} DOFs")
    with interrupt.deferred():
        return _replay(problem, recording)


def _replay(problem: Problem, recording: Recording) -> SimulationResult:
    """Step the recording's frames, and gather the result."""
    started = time.perf_counter()
    run = _replay_setup(problem)
    state = _State(run.fatigue.initial_state(), recording.q[0].copy())
    packed, width = run.torque_model.default_loads, LOAD_PARAMETERS
    gave_out = np.zeros(len(run.names), dtype=bool)
    for step, now in enumerate(recording.time.tolist()):
        if interrupt.requested():
            state.events.append(Event(now, "interrupted", "", "Ctrl-C: the run stopped here"))
            state.stop = "interrupted"
            break
        state.q = recording.q[step]
        dt = now - float(recording.time[step - 1]) if step else 0.0
        held = None if recording.held is None else packed * np.repeat(recording.held[step], width)
        loads, over, _ = _update_fatigue(run, state, step, now, dt, held)
        for k in np.flatnonzero((state.levels >= 1.0) & ~gave_out):
            cause = "load above strength" if k in over else "fatigue reached 1"
            detail = f"{cause}: the model's group gives out here; the recording goes on"
            state.events.append(Event(now, "exhausted", run.names[k], detail))
        gave_out |= state.levels >= 1.0
        residuals = np.zeros(0) if run.hierarchy is None else run.hierarchy.residual_norms(state.q)
        state.record.add(
            **_row(
                run.position,
                run.constraint,
                now,
                state.q,
                state.torques,
                loads,
                state.levels,
                residuals,
                RECORDED,
            )
        )
    state.events = [e for e in state.events if e.kind not in ("constraint_on", "constraint_off")]
    return _result(run, state, started, recording)


def _replay_setup(problem: Problem) -> _Setup:
    """What a replay builds once: the torque and fatigue models, the hysteresis, the
    effector's compiled position and, if the problem has tasks, their levels."""
    hierarchy = problem.hierarchy() if problem.spec.tasks else None
    settings = constraint_settings(problem)
    effector, line = _tracked(problem, hierarchy)
    return _Setup(
        problem,
        RECORDED,
        settings,
        hierarchy,
        None,
        None,
        problem.torque_model(),
        problem.fatigue,
        FatigueConstraint(problem.body, problem.passive, settings),
        effector,
        line,
        _effector(problem.body, effector),
        [h.name for h in problem.body.half_joints],
        "" if hierarchy is None else hierarchy.level_names()[0],
        math.nan,
        None,
    )


@dataclass(frozen=True)
class _Setup:
    """What a run builds once, before its loop: the solvers (``kept_solvers`` on the
    whole-body adjustment's kept levels, None with the paper's; no solver in a replay), the
    torque and fatigue models, the constraint, the tracked effector and line, the compiled
    effector position, the half-joint names, the top level's name, the step [s] and the
    schedule."""

    problem: Problem
    solver: str
    settings: ConstraintSettings
    hierarchy: TaskHierarchy | None
    solvers: _Solvers | None
    kept_solvers: _Solvers | None
    torque_model: TorqueModel
    fatigue: FatigueModel
    constraint: FatigueConstraint
    effector: str
    line: Line | None
    position: Compiled
    names: list[str]
    top: str
    dt: float
    schedule: Schedule | None

    @property
    def depth(self) -> int:
        """The number of priority levels (0: a replay of a problem without tasks)."""
        return 0 if self.hierarchy is None else self.hierarchy.depth


@dataclass
class _State:
    """What the loop carries from step to step: the fatigue model's state, the posture
    [rad], its torques and fatigue levels, the last IK answer and inequality, the owner whose
    ``no_reduction`` was reported, whether level 1 was held, the rows and events so far, why
    the run stopped, the solver statistics (IK wall time [s]) and ``drift``: the owner of the
    last step's constraint and the posture [rad] that step started from, to predict the
    next start from (``_predicted``)."""

    fatigue_state: np.ndarray
    q: np.ndarray
    torques: Torques | None = None
    levels: np.ndarray | None = None
    result: IKResult | None = None
    before: Inequality | None = None
    unreduced: int | None = None
    held: bool = True
    record: _Recorder = field(default_factory=_Recorder)
    events: list[Event] = field(default_factory=list)
    stop: Stop = "completed"
    ik_time: float = 0.0
    failures: int = 0
    fallbacks: int = 0
    iterations: int = 0
    reused: int = 0
    drift: tuple[int, np.ndarray] | None = None


@dataclass(frozen=True)
class _Built:
    """What a run builds from the body, the posture, the loads and the tasks alone, kept for
    the next run of the same: the hierarchy and the whole-body adjustment to copy, the
    torque model to share (one thread). Built on a ``Shape`` (the body's numbers as
    symbols), the next run of another person (stature, mass, age, strength) rebinds it."""

    hierarchy: TaskHierarchy
    torque_model: TorqueModel
    whole_body: WholeBodyAdjustment | None


#: Problem structures whose builds a thread keeps (a what-if grid, a duty-cycle search or a
#: second run of one problem varies the fatigue settings, the schedule or the duration).
KEPT_BUILDS = 4
_builds = threading.local()

#: The body keys that set a person's numbers (``Shape``), not the structure of what is built.
PERSON_KEYS = frozenset({"stature_m", "mass_kg", "age_years", "hip_height_m", "segments"})
#: A half-joint's keys that set its strength's value only.
STRENGTH_VALUE_KEYS = frozenset({"strength_Nm", "strength_scale", "strength_ratio"})


def _built(problem: Problem, keep_levels: int | None) -> _Built:
    """The problem's hierarchy, torque model and (``keep_levels`` given) whole-body
    adjustment, built once per structure in this thread on its ``Shape`` and bound to this
    body's numbers."""
    values, tasks = numbers(problem.body, problem.strength), problem.task_objects()
    key = (_structure(problem, tasks), np.flatnonzero(values).tobytes(), keep_levels)
    if not hasattr(_builds, "kept"):
        _builds.kept = OrderedDict()
    kept: OrderedDict = _builds.kept
    if key in kept:
        kept.move_to_end(key)
    else:
        kept[key] = _build(problem, tasks, keep_levels)
        while len(kept) > KEPT_BUILDS:
            kept.popitem(last=False)
    template: _Built = kept[key]
    own = values[values != 0.0]
    hierarchy = template.hierarchy.rebound(tasks, own)
    return _Built(hierarchy, template.torque_model.rebound(own), template.whole_body)


def torque_model(problem: Problem) -> TorqueModel:
    """The torque model a simulation of ``problem`` uses: its build in this thread (the one
    its last run made or rebound, without building again), bound to its body's numbers; a
    problem without tasks (a recording's) builds its own."""
    if not problem.tasks:
        return problem.torque_model()
    settings = constraint_settings(problem)
    keep_levels = settings.keep_levels if settings.adjustment == "whole_body" else None
    return _built(problem, keep_levels).torque_model


def _build(problem: Problem, tasks: list[Task], keep_levels: int | None) -> _Built:
    """The hierarchy of ``tasks``, the torque model and the whole-body adjustment on the
    problem's ``Shape`` (its body's numbers symbols)."""
    shape = Shape.of(problem.body, problem.strength)
    pair = (shape.symbols, shape.values(problem.body, problem.strength))
    torque_model = TorqueModel(shape.body, problem.loads, problem.passive, shape.strength, pair)
    hierarchy = TaskHierarchy(shape.body, _shaped(tasks, shape, problem, torque_model), pair)
    whole_body = None
    if keep_levels is not None and _effort_comfort(problem) is not None:
        whole_body = WholeBodyAdjustment(torque_model, hierarchy, k=0.0, keep_levels=keep_levels)
    return _Built(hierarchy, torque_model, whole_body)


def _shaped(tasks: list[Task], shape: Shape, problem: Problem, torques: TorqueModel) -> list[Task]:
    """``tasks`` with each comfort level's strengths those of ``shape`` (its values symbols)
    and, when it counts the problem's loads and passive torques, the active torque of the
    torque model ``torques`` (not built again)."""
    active = (torques.tau_act, torques.load_symbols)
    return [
        replace(
            t,
            strength=shape.strength,
            active=active if (t.loads, t.passive) == (torques.loads, problem.passive) else None,
        )
        if isinstance(t, Comfort)
        else t
        for t in tasks
    ]


def _structure(problem: Problem, tasks: list[Task]) -> str:
    """What a build depends on besides the body's numbers: the file's body, posture, loads
    and tasks without the keys that set a person's numbers, the strength models with their
    values left out, the passive curves, the joint limits and the comfort measure."""
    spec = problem.spec.model_dump(
        include={"body", "posture_deg", "loads", "tasks"}, mode="json", warnings=False
    )
    body = {k: v for k, v in spec["body"].items() if k not in PERSON_KEYS}
    kept = {
        name: {k: v for k, v in given.items() if k not in STRENGTH_VALUE_KEYS and v is not None}
        for name, given in body["half_joints"].items()
    }
    body["half_joints"] = {name: given for name, given in kept.items() if given}
    strengths = [
        repr(replace(model, value=0.0) if scalable(model) else model)
        for model in (problem.strength[h.name] for h in problem.body.half_joints)
    ]
    measures = [t.measure for t in tasks if isinstance(t, Comfort)]
    return repr(
        (
            {**spec, "body": body},
            strengths,
            sorted((k, repr(v)) for k, v in problem.passive.items()),
            problem.body.lower.tobytes(),
            problem.body.upper.tobytes(),
            problem.posture.tobytes(),
            [
                (m.neutral.tobytes(), m.joint_weights.tobytes(), m.term_weights, m.zone)
                for m in measures
            ],
        )
    )


def _setup(problem: Problem, solver: str | None) -> _Setup:
    """Check the adjustment's settings and build, once, every object the steps use."""
    spec, body = problem.spec, problem.body
    name = solver or spec.solver.name
    settings = constraint_settings(problem)
    keep_levels = settings.keep_levels if settings.adjustment == "whole_body" else None
    built = _built(problem, keep_levels)
    hierarchy, torque_model = built.hierarchy.copy(), built.torque_model
    solvers = _Solvers(name, problem, hierarchy)
    fatigue = problem.fatigue
    if settings.keep_levels > hierarchy.depth:
        raise ProblemError(
            problem.path,
            "fatigue.keep_levels",
            settings.keep_levels,
            f"at most the number of priority levels ({hierarchy.depth})",
        )
    whole_body, kept_solvers = None, None
    if settings.adjustment == "whole_body":
        if _effort_comfort(problem) is None:
            raise ProblemError(
                problem.path,
                "fatigue.adjustment",
                "whole_body",
                "a problem whose lowest level is a comfort task counting effort "
                "(kind = 'comfort', measure = 'discomfort_effort'), or adjustment = 'paper'",
            )
        whole_body = built.whole_body.rebind(
            hierarchy, k=settings.fatigue_weight, torque_model=torque_model
        )
        kept_solvers = _Solvers(name, problem, whole_body.kept_hierarchy)
    constraint = FatigueConstraint(body, problem.passive, settings, hierarchy, whole_body)
    effector, line = _tracked(problem, hierarchy)
    return _Setup(
        problem,
        name,
        settings,
        hierarchy,
        solvers,
        kept_solvers,
        torque_model,
        fatigue,
        constraint,
        effector,
        line,
        _effector(body, effector),
        [h.name for h in body.half_joints],
        hierarchy.level_names()[0],
        spec.simulation.time_step_s,
        Schedule.of(problem),
    )


def _rest_step(run: _Setup, state: _State, now: float) -> None:
    """A rest step at ``now`` [s]: no load, every group recovers, the last posture recorded."""
    loads = np.zeros(len(run.names))
    state.fatigue_state = run.fatigue.step(state.fatigue_state, loads, run.dt)
    state.levels = run.fatigue.level(state.fatigue_state, loads)
    state.events += run.constraint.update(state.levels, now)
    idle = np.full(run.depth, math.nan)
    row = _row(run.position, run.constraint, now, state.q, None, loads, state.levels, idle, "")
    state.record.add(**row)


def _hold_step(run: _Setup, state: _State, step: int, now: float, stop_at_threshold: bool) -> bool:
    """A hold step at ``now`` [s]: constraint, IK, fatigue, checks, row; True if the run ends."""
    inequality, goal = _plan_constraint(run, state, now)
    _solve_ik(run, state, inequality, now)
    loads, over, changes = _update_fatigue(run, state, step, now, run.dt)
    _check_level_one(run, state, step, now)
    row = _row(
        run.position,
        run.constraint,
        now,
        state.q,
        state.torques,
        loads,
        state.levels,
        state.result.residuals,
        state.result.solver,
        goal,
    )
    state.record.add(**row)
    return _ends(run, state, over, changes, now, stop_at_threshold)


def _plan_constraint(
    run: _Setup, state: _State, now: float
) -> tuple[Inequality | None, Goal | None]:
    """The step's constraint (inequality, goal) from the last step, with its events."""
    constraint, names = run.constraint, run.names
    was_blocked = constraint.blocked
    planned = (
        constraint.hyperplane(state.q, state.torques, state.levels)
        if state.torques is not None
        else None
    )
    inequality, goal = planned if planned is not None else (None, None)
    if goal is not None and inequality is None and state.unreduced != constraint.owner:
        state.unreduced = constraint.owner
        state.events.append(
            Event(
                now,
                "no_reduction",
                names[constraint.owner],
                f"{goal.case}: no posture the constraint could move to carries less; "
                "the posture stays",
            )
        )
    if constraint.owner is None:
        state.unreduced = None
    if constraint.blocked and not was_blocked and constraint.owner is not None:
        state.events.append(
            Event(
                now,
                "constraint_blocked",
                names[constraint.owner],
                "the goal is not reachable while the kept levels hold",
            )
        )
    return inequality, goal


def _solve_ik(run: _Setup, state: _State, inequality: Inequality | None, now: float) -> None:
    """The step's posture: the last one when nothing changed, else the IK's (with fallback)
    from the posture ``_predicted`` for the step, solved again by the same solver under the
    plane's other side when the other tasks carried it past the plane's step
    (``FatigueConstraint.overshot``); that answer is kept when it converges and loses no
    level 1 the first held, else the first stands."""
    tic = time.perf_counter()
    result = state.result
    unchanged = (
        result is not None and result.success and inequality is None and state.before is None
    )
    state.before = inequality
    owner = run.constraint.owner
    if unchanged:
        state.reused += 1
    else:
        kept = run.kept_solvers is not None and owner is not None
        solvers = run.kept_solvers if kept else run.solvers
        start = _predicted(run, state, inequality, owner)
        result, spent, detail = _solve_step(
            solvers, state.q, inequality, retry=state.held, start=start
        )
        swapped = None if inequality is None else run.constraint.overshot(inequality, result.q)
        if swapped is not None and result.success:  # by the same solver, or not at all
            again = solvers.named(result.solver).solve(state.q, swapped)
            spent += again.iterations
            if again.success and (again.achieved[0] or not result.achieved[0]):
                result, inequality = again, swapped
                run.constraint.hold(swapped)
        if kept:
            result = replace(result, residuals=run.hierarchy.residual_norms(result.q))
        state.iterations += spent
        if detail:
            state.events.append(Event(now, "solver_fallback", "", detail))
            state.fallbacks += 1
    state.ik_time += time.perf_counter() - tic
    state.failures += not result.success
    moving = inequality is not None and owner is not None and result.success
    state.drift = (owner, state.q) if moving else None
    state.result, state.q = result, result.q


def _predicted(
    run: _Setup, state: _State, inequality: Inequality | None, owner: int | None
) -> np.ndarray | None:
    """Where to start this step's IK [rad] under the whole-body adjustment: while one
    group's load bound moves the posture step after step, the last posture plus the last
    step's change, within the joint limits (the secant predictor of continuation methods).
    None (start from the last posture) at the bound's first step, when its owner changes,
    without one, after a step the IK failed, and under the paper's strategies.

    Converged answers agree to the solvers' tolerances (tests/test_warm_start.py). On the
    20-minute standing wall hold the IK spends 357 instead of 1387 nullspace iterations
    (732 instead of 2187 IPOPT ones). Under the paper's plane, which moves one joint towards
    its goal angle, it spent more: 386 instead of 254 IPOPT iterations on the 2-DOF arm,
    682 instead of 543 nullspace ones at -45°."""
    if run.constraint.whole_body is None or inequality is None:
        return None
    if state.drift is None or state.drift[0] != owner:
        return None
    body = run.problem.body
    return np.clip(2.0 * state.q - state.drift[1], body.lower, body.upper)


def _update_fatigue(
    run: _Setup,
    state: _State,
    step: int,
    now: float,
    dt: float,
    held: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, list[Event]]:
    """Torques and fatigue at the new posture holding the loads ``held`` (the torque
    model's parameter vector; None: every load), over the ``dt`` [s] since the step before:
    the loads [%MVC], groups over strength, events."""
    state.torques = run.torque_model.evaluate(state.q, held)
    loads = state.torques.load_pct_mvc
    if step > 0:
        state.fatigue_state = run.fatigue.step(state.fatigue_state, loads, dt)
    levels = run.fatigue.level(state.fatigue_state, loads)
    over = np.flatnonzero(loads > STRENGTH_PCT_MVC)
    for k in over:
        state.events.append(
            Event(
                now,
                "over_strength",
                run.names[k],
                f"load {loads[k]:.2f} %MVC exceeds the group's strength",
            )
        )
    levels[over] = 1.0
    state.levels = levels
    changes = run.constraint.update(levels, now)
    state.events += changes
    return loads, over, changes


def _check_level_one(run: _Setup, state: _State, step: int, now: float) -> None:
    """Level 1 after the IK: ``task_not_held`` when lost, ``never_held`` at the start."""
    result = state.result
    if not result.achieved[0]:
        if step == 0:
            detail = (
                f"level 1 not achieved at the start: residual {result.residuals[0]:.3g} "
                f"{run.hierarchy.level_units()[0]} > {ACHIEVED_TOLERANCE:g}; the task is "
                "never held"
            )
            state.stop = "never_held"
        else:
            detail = f"level-1 residual {result.residuals[0]:.3g}"
        if state.held:
            state.events.append(Event(now, "task_not_held", run.top, detail))
    state.held = result.achieved[0]


def _ends(
    run: _Setup,
    state: _State,
    over: np.ndarray,
    changes: list[Event],
    now: float,
    stop_at_threshold: bool,
) -> bool:
    """Whether the run ends here: never held, a group exhausted, or (if asked) the threshold."""
    if state.stop == "never_held":
        return True
    levels = state.levels
    if levels.max() >= 1.0:
        worst = int(np.argmax(levels))
        cause = "load above strength" if worst in over else "fatigue reached 1"
        state.events.append(
            Event(
                now,
                "exhausted",
                run.names[worst],
                f"{cause}: the task can no longer be held",
            )
        )
        state.stop = "exhausted"
        return True
    if stop_at_threshold and any(e.kind == "fatigue_threshold" for e in changes):
        state.stop = "fatigue_threshold"
        return True
    return False


def _result(
    run: _Setup, state: _State, started: float, recording: Recording | None = None
) -> SimulationResult:
    """The run's result, with the wall time [s] since ``started`` (``time.perf_counter``);
    a replay's ``recording``."""
    hierarchy = run.hierarchy
    levels = () if hierarchy is None else hierarchy.levels
    held = None if recording is None else recording.held
    timeline = _timeline(run, state.record, held)
    return SimulationResult(
        run.problem,
        run.solver,
        run.settings,
        run.effector,
        tuple(t for level in levels for t in level),
        () if hierarchy is None else tuple(hierarchy.level_names()),
        () if hierarchy is None else tuple(hierarchy.level_units()),
        timeline,
        state.events,
        state.stop,
        run.problem.spec.simulation.duration_s if recording is None else recording.duration_s,
        time.perf_counter() - started,
        state.ik_time,
        state.failures,
        state.fallbacks,
        state.iterations,
        state.reused,
        run.schedule,
        recording,
    )


def _timeline(run: _Setup, record: _Recorder, held: np.ndarray | None = None) -> Timeline:
    """The recorded rows as the timeline's arrays, the distance along the line [m], balance
    (with the loads each step holds: ``held``, a recording's, per frame 0/1 per load)."""
    body, names = run.problem.body, run.names
    count = len(record.rows.get("q", []))
    held = None if held is None else held[:count]
    postures = _rows(record, "q", count, body.n)
    effector_path = record.array("effector") if count else np.zeros((0, 3))
    along = None
    if run.line is not None:
        direction = np.asarray(run.line.direction) / np.linalg.norm(run.line.direction)
        along = (effector_path - np.asarray(run.line.point)) @ direction
    return Timeline(
        record.array("time") if count else np.zeros(0),
        postures,
        effector_path,
        along,
        *(
            _rows(record, k, count, width)
            for k, width in (
                ("external", body.n),
                ("passive", body.n),
                ("active", body.n),
                ("load", len(names)),
                ("fatigue", len(names)),
                ("fatigued", len(names)),
                ("owner", None),
                ("goal", None),
            )
        ),
        list(record.rows.get("case", [])),
        _rows(record, "residuals", count, run.depth),
        list(record.rows.get("solver", [])),
        list(record.rows.get("phase", [])),
        _balance(run.problem, postures, held) if count else None,
        held,
    )


def _effector(body: BodyModel, name: str) -> Compiled:
    """The landmark ``name``'s position [m] as a compiled ``x(q)`` (a call a step: 2 µs in
    buffers instead of 30 µs as a CasADi call)."""
    return Compiled(ca.Function("effector", [body.q], [body.landmark(name)], ["q"], ["x"]))


def _row(
    position: Compiled,
    constraint: FatigueConstraint,
    now: float,
    q: np.ndarray,
    torques: Torques | None,
    loads: np.ndarray,
    levels: np.ndarray,
    residuals: np.ndarray,
    solver: str,
    goal: Goal | None = None,
) -> dict[str, object]:
    """A timeline row at ``now`` [s]: a hold step's (``torques`` given; ``solver`` the IK
    solver that gave the posture, or ``recorded``) or a rest step's (None: the last held
    posture ``q`` [rad], NaN torques, no solver); the levels' ``residuals``."""
    idle = np.full(len(q), math.nan)
    return {
        "time": now,
        "q": q,
        "effector": position(q=q)["x"].copy(),
        "external": idle if torques is None else torques.external,
        "passive": idle if torques is None else torques.passive,
        "active": idle if torques is None else torques.active,
        "load": loads,
        "fatigue": levels,
        "fatigued": constraint.fatigued.copy(),
        "owner": -1 if constraint.owner is None or solver == RECORDED else constraint.owner,
        "goal": math.nan if goal is None else goal.angle,
        "case": "" if goal is None else goal.case,
        "residuals": residuals,
        "solver": solver,
        "phase": "rest" if torques is None else "hold",
    }


def _solve_step(
    solvers: _Solvers,
    q: np.ndarray,
    inequality: Inequality | None,
    *,
    retry: bool,
    start: np.ndarray | None = None,
) -> tuple[IKResult, int, str]:
    """The step's posture from ``q`` [rad] (the first solver from ``start`` if given, and
    from ``q`` again if it fails there), the IK iterations spent, and why the other solver
    gave it ('' if the first did). The other solver is tried when the first fails or stalls,
    and, when ``retry`` (level 1 held at the last step), when the first leaves level 1
    unachieved: both are local methods, and one may stop in a local minimum of a level the
    other achieves. Its answer is kept when it succeeds and the first did not, or when it
    achieves level 1 and the first did not. While level 1 stays lost the first solver's
    answer stands, so a task broken for good costs one solve a step."""

    def stands(answer: IKResult) -> bool:
        return answer.success and (answer.achieved[0] or not retry)

    result = solvers.primary.solve(q if start is None else start, inequality)
    spent = result.iterations
    if start is not None and not stands(result):
        result = solvers.primary.solve(q, inequality)
        spent += result.iterations
    if stands(result):
        return result, spent, ""
    other = solvers.fallback().solve(q, inequality)
    spent += other.iterations
    if not result.success:
        detail = f"{result.solver}: {result.status}; {other.solver}: {other.status}"
        return (other if other.success else result), spent, detail
    if other.success and other.achieved[0]:
        detail = (
            f"{result.solver}: level 1 not achieved (residual {result.residuals[0]:.3g}); "
            f"{other.solver}: achieved ({other.residuals[0]:.3g})"
        )
        return other, spent, detail
    return result, spent, ""


def _balance(
    problem: Problem, postures: np.ndarray, held: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray] | None:
    """The centre of mass over the floor and its margin in the support polygon per step,
    with the loads each step holds (``held``: per step 0/1 per load; None: all)."""
    support = Support(problem.body)
    if held is None:
        carried = [(load.at, load.mass) for load in problem.loads if load.mass > 0]
        return support.balance(postures, carried)
    out = None
    for pattern in np.unique(held, axis=0):
        steps = np.flatnonzero((held == pattern).all(axis=1))
        carried = [
            (load.at, load.mass)
            for load, on in zip(problem.loads, pattern, strict=True)
            if on and load.mass > 0
        ]
        part = support.balance(postures[steps], carried)
        if part is None:
            return None
        if out is None:
            out = (np.zeros((len(postures), part[0].shape[1])), np.zeros(len(postures)))
        out[0][steps], out[1][steps] = part
    return out


def _rows(record: _Recorder, key: str, count: int, width: int | None) -> np.ndarray:
    """The recorded rows of ``key`` as one array (an empty one of the right shape if none)."""
    if count:
        return record.array(key)
    return np.zeros((0,) if width is None else (0, width))


def _tracked(problem: Problem, hierarchy: TaskHierarchy | None) -> tuple[str, Line | None]:
    """The effector of the highest-priority task that has one (else the body's first
    landmark), and the first line task."""
    tasks = [] if hierarchy is None else [t for level in hierarchy.levels for t in level]
    effectors = [t.effector for t in tasks if hasattr(t, "effector")]
    line = next((t for t in tasks if isinstance(t, Line)), None)
    return (effectors[0] if effectors else next(iter(problem.body.landmarks))), line
