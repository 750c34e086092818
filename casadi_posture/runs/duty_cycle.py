"""The sustainable duty cycle of a task: for a rest time ``t_off`` per cycle, the longest hold
``t_on`` per cycle with which no muscle group reaches the fatigue threshold over a horizon
(by default an 8-hour shift).

"Reaches the fatigue threshold": on some step of the simulated schedule a group's fatigue
level is at least ``fatigue.fatigue_threshold`` (a group over its strength counts, being
exhausted at once): the moment the fatigue-reducing constraint would engage and the
posture would start to drift. Each trial simulates the problem with ``[schedule]`` set to
``t_on``, ``t_off`` for ``simulation.duration_s`` = the horizon, stopping at the first such
step.

Holds are counted in whole time steps (``t_on = n·dt``; ``t_off`` rounds up to whole steps
as in every schedule). First the continuous hold (``t_on`` = the horizon): if it stays
below the threshold, the task is sustainable held continuously for the horizon. Then one
step of hold per cycle: if even that reaches the threshold, no duty cycle works. Otherwise
bisection on n keeps a bracket ``n_ok < n_fail`` of simulated holds (``n_ok`` below the
threshold over the horizon, ``n_fail`` reaching it) until ``(n_fail − n_ok)·dt ≤
tolerance`` and the duty cycles of its ends, ``n·dt / (n·dt + t_off)``, differ by at most
``precision`` of the lower one, or the bracket is one step wide (the time step then limits
it, and says so). The bisection assumes that a longer hold per cycle never tires less;
both ends of the reported bracket are simulations, whatever the assumption.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from casadi_posture import interrupt
from casadi_posture.ergonomics.acceptable_effort import Guideline
from casadi_posture.errors import ProblemError
from casadi_posture.ik.solvers import check_solver
from casadi_posture.output.plain import dumps
from casadi_posture.output.results import (
    balance_margin_min,
    over_strength_at_start,
    write_table,
)
from casadi_posture.problem import Problem, problem_from_data
from casadi_posture.simulation import SimulationResult, simulate, whole_steps
from casadi_posture.spec.schema import MAX_STEPS
from casadi_posture.static import tied

#: Default bisection tolerance on t_on [s] (at least one time step).
DEFAULT_TOLERANCE_S = 5.0
#: Default relative precision of the duty cycle's bracket: its ends within 5 % of the lower.
DEFAULT_PRECISION = 0.05
#: Default horizon [s]: an 8-hour shift (a problem file's duration is one run's, often 10 or
#: 30 minutes, too short to say a hold is sustainable).
SHIFT_S = 8 * 3600.0

#: What a search found: a bracket of holds; sustainable held continuously over the horizon; no
#: hold of even one step sustainable; the task never held at the start; stopped by Ctrl-C.
Verdict = Literal["bracketed", "continuous", "none", "never_held", "interrupted"]


@dataclass(frozen=True)
class Trial:
    """One simulation of the search: the hold per cycle [s], whether a group reached the
    fatigue threshold (None: interrupted before the horizon), when [s] and which group, the
    largest fatigue level of the run, IK steps no solver certified, the groups over their
    strength at the start, the smallest balance margin [m] (None: no balance task) and its
    wall time [s]."""

    t_on_s: float
    reached: bool | None
    threshold_s: float | None
    half_joint: str | None
    max_fatigue: float
    ik_failures: int
    over_strength: list[str]
    balance_margin_m: float | None
    wall_time_s: float


@dataclass(frozen=True)
class Effort:
    """The effort of a hold, for Potvin's guideline (ergonomics/acceptable_effort.py): the
    most loaded group on the first hold step, its load [%MVC] and joint region."""

    half_joint: str
    region: str
    load_pct_mvc: float


@dataclass(frozen=True)
class DutyCycle:
    """The sustainable duty cycle of a problem for one rest time.

    ``t_off_s`` is the rest asked for and ``rest_s`` the rest on the step grid [s];
    ``sustainable_t_on_s`` the longest hold found to stay below the threshold over the
    horizon and ``failing_t_on_s`` the shortest found to reach it (None where no such
    simulation: sustainable held continuously, or none sustainable); ``horizon_s`` the
    simulated time [s] over which the threshold must not be reached; ``notes`` the
    problem's (spec/slips.py)."""

    problem: str
    t_off_s: float
    rest_s: float
    horizon_s: float
    tolerance_s: float
    precision: float
    time_step_s: float
    fatigue_threshold: float
    verdict: Verdict
    sustainable_t_on_s: float | None
    failing_t_on_s: float | None
    trials: list[Trial]
    wall_time_s: float
    effort: Effort | None = None
    runs: dict[str, SimulationResult] = field(default_factory=dict, repr=False)
    notes: tuple[str, ...] = ()

    @property
    def duty_cycle_pct(self) -> float | None:
        """``t_on/(t_on + t_off)`` of the sustainable hold [%]: 100 when the task is
        sustainable held continuously, 0 when no hold is; None when the search was cut short."""
        if self.verdict == "continuous":
            return 100.0
        if self.verdict == "none":
            return 0.0
        if self.sustainable_t_on_s is None or self.verdict != "bracketed":
            return None
        return 100.0 * self.sustainable_t_on_s / (self.sustainable_t_on_s + self.rest_s)

    @property
    def duty_cycle_bracket_pct(self) -> tuple[float, float] | None:
        """The duty cycles [%] of the bracket's ends, sustainable and failing (None unless
        bracketed)."""
        ok, fail = self.sustainable_t_on_s, self.failing_t_on_s
        if self.verdict != "bracketed" or ok is None or fail is None:
            return None
        return 100.0 * ok / (ok + self.rest_s), 100.0 * fail / (fail + self.rest_s)

    @property
    def step_limited(self) -> bool:
        """Whether the time step, not the tolerance or the precision, set the bracket's
        width (one step wide and still wider than asked)."""
        bracket = self.duty_cycle_bracket_pct
        if bracket is None or self.failing_t_on_s is None or self.sustainable_t_on_s is None:
            return False
        one_step = self.failing_t_on_s - self.sustainable_t_on_s <= self.time_step_s * 1.000001
        return one_step and bracket[1] - bracket[0] > self.precision * bracket[0] * 1.000001

    @property
    def flags(self) -> list[str]:
        """Why the answer cannot be used as it is, one line each (empty: it can)."""
        out = []
        if self.verdict == "interrupted":
            out.append("interrupted: the bracket is the one found so far")
        if self.verdict == "never_held":
            out.append("task never held: level 1 not achieved at the start")
        failed = sum(t.ik_failures for t in self.trials)
        if failed:
            out.append(f"{failed} steps where neither IK solver converged in the trials")
        over = sorted({g for t in self.trials for g in t.over_strength})
        if over:
            out.append(
                f"over strength at the start ({', '.join(over)}): the load cannot be held "
                "at all, whatever the rest"
            )
        fallen = [t for t in self.trials if (t.balance_margin_m or 0.0) < 0]
        if fallen:
            out.append(
                f"balance lost in {len(fallen)} of {len(self.trials)} simulations: the "
                f"centre of mass leaves the support polygon by up to "
                f"{-min(t.balance_margin_m for t in fallen):.3g} m"
            )
        return out

    def guideline(self) -> dict[str, Any] | None:
        """Potvin's (2012) shift-long guideline beside the answer: the hold's effort, the
        largest duty cycle [%] the guideline accepts for it, the effort [%MVC] it accepts at
        our sustainable duty cycle (None when none is), and whether its upper-limb data
        cover the group's region (None without a held step)."""
        if self.effort is None:
            return None
        rule = Guideline.from_data()
        ours = self.duty_cycle_pct
        return {
            "source": "Potvin 2012, Human Factors 54(2):175-188: MAE = 1 - (DC - 1/28800)^0.24",
            "half_joint": self.effort.half_joint,
            "region": self.effort.region,
            "effort_pct_mvc": self.effort.load_pct_mvc,
            "acceptable_duty_cycle_pct": rule.duty_cycle_pct(self.effort.load_pct_mvc),
            "acceptable_effort_at_duty_cycle_pct_mvc": (  # none when no duty cycle works
                rule.mae_pct_mvc(ours) if ours else None
            ),
            "region_in_guideline_data": rule.covers(self.effort.region),
            "rms_difference_pct_mvc": rule.rms_difference_pct_mvc,
        }

    def summary(self) -> dict[str, Any]:
        """The search as plain data (duty_cycle.json): settings, verdict, bracket, duty
        cycle [%], Potvin's guideline beside it, every trial, the wall time [s], the
        problem's notes and the flags."""
        return {
            "problem": self.problem,
            "t_off_s": self.t_off_s,
            "rest_s": self.rest_s,
            "horizon_s": self.horizon_s,
            "tolerance_s": self.tolerance_s,
            "precision": self.precision,
            "time_step_s": self.time_step_s,
            "fatigue_threshold": self.fatigue_threshold,
            "verdict": self.verdict,
            "sustainable_t_on_s": self.sustainable_t_on_s,
            "failing_t_on_s": self.failing_t_on_s,
            "duty_cycle_pct": self.duty_cycle_pct,
            "duty_cycle_bracket_pct": self.duty_cycle_bracket_pct,
            "bracket_limited_by_time_step": self.step_limited,
            "guideline": self.guideline(),
            "simulations": len(self.trials),
            "wall_time_s": self.wall_time_s,
            "trials": [t.__dict__ for t in self.trials],
            "notes": list(self.notes),
            "flags": self.flags,
        }


def check_seconds(value: float, key: str, path: object, *, positive: bool) -> float:
    """A time [s] given for the search: finite, and > 0 (``positive``) or ≥ 0; else a
    ``ProblemError`` naming ``key``."""
    if not (math.isfinite(value) and (value > 0 if positive else value >= 0)):
        raise ProblemError(path, key, value, f"a finite time {'> 0' if positive else '≥ 0'} s")
    return float(value)


def duty_cycle(
    problem: Problem,
    t_off_s: float,
    *,
    horizon_s: float | None = None,
    tolerance_s: float | None = None,
    precision: float = DEFAULT_PRECISION,
    solver: str | None = None,
) -> DutyCycle:
    """The longest hold per cycle with rest ``t_off_s`` [s] that never reaches the fatigue
    threshold within ``horizon_s`` [s] (default ``SHIFT_S``, an 8-hour shift),
    to ``tolerance_s`` [s] (default 5 s, at least one time step) and the duty cycle to
    ``precision`` (relative, default 5 %), by bisection over simulations (module
    docstring). Ctrl-C stops it between two steps of a trial: the
    verdict is then ``interrupted`` and the bracket is the one found so far."""
    path, spec = problem.path, problem.spec
    check_solver(solver, path)
    dt = spec.simulation.time_step_s
    t_off = check_seconds(t_off_s, "t_off_s", path, positive=False)
    horizon = check_seconds(
        SHIFT_S if horizon_s is None else horizon_s,
        "horizon_s",
        path,
        positive=True,
    )
    tolerance = check_seconds(
        max(DEFAULT_TOLERANCE_S, dt) if tolerance_s is None else tolerance_s,
        "tolerance_s",
        path,
        positive=True,
    )
    if tolerance < dt - 1e-9 * dt:
        raise ProblemError(path, "tolerance_s", tolerance, f"at least the time step, {dt:g} s")
    if not (math.isfinite(precision) and 0.0 < precision <= 1.0):
        raise ProblemError(path, "precision", precision, "a relative width above 0, at most 1")
    steps = math.floor(horizon / dt + 1e-9)
    if steps < 1:
        raise ProblemError(path, "horizon_s", horizon, f"at least the time step, {dt:g} s")
    if steps > MAX_STEPS:
        raise ProblemError(
            path,
            "horizon_s",
            horizon,
            f"at most {MAX_STEPS} time steps of {dt:g} s ({MAX_STEPS * dt:g} s): a shorter "
            "horizon (--horizon) or a longer simulation.time_step_s",
        )
    start = time.perf_counter()
    trials: list[Trial] = []
    results: dict[int, SimulationResult] = {}

    def trial(hold_steps: int) -> bool | None:
        """Simulate ``hold_steps`` of hold per cycle: whether the threshold was reached."""
        overrides = {
            "schedule.t_on_s": hold_steps * dt,
            "schedule.t_off_s": t_off,
            "simulation.duration_s": steps * dt,
        }
        case = problem_from_data(problem.data, path, overrides)
        result = simulate(case, solver, stop_at_threshold=True)
        crossing = next((e for e in result.events if e.kind == "fatigue_threshold"), None)
        reached = crossing is not None or (None if result.stop == "interrupted" else False)
        trials.append(
            Trial(
                hold_steps * dt,
                reached,
                None if crossing is None else crossing.time_s,
                None if crossing is None else crossing.half_joint,
                float(result.timeline.fatigue.max(initial=0.0)),
                result.ik_failures,
                over_strength_at_start(result),
                balance_margin_min(result),
                result.wall_time_s,
            )
        )
        results[hold_steps] = result
        return reached

    def answer(verdict: Verdict, ok: int | None, fail: int | None) -> DutyCycle:
        ends = (("stays below", ok), ("reaches", fail))
        return DutyCycle(
            str(path),
            t_off,
            whole_steps(t_off, dt) * dt,
            steps * dt,
            tolerance,
            precision,
            dt,
            spec.fatigue.fatigue_threshold,
            verdict,
            None if ok is None else ok * dt,
            None if fail is None else fail * dt,
            trials,
            time.perf_counter() - start,
            _effort(results[steps]) if steps in results else None,
            {label: results[n] for label, n in ends if n is not None},
            problem.notes,
        )

    tolerance_steps = max(1, math.floor(tolerance / dt + 1e-9))
    with interrupt.deferred():
        continuous = trial(steps)
        if results[steps].stop == "never_held":
            return answer("never_held", None, None)
        if continuous is None:
            return answer("interrupted", None, None)
        if not continuous:
            return answer("continuous", steps, None)
        shortest = trial(1) if steps > 1 else continuous
        if shortest is None:
            return answer("interrupted", None, steps)
        if shortest:
            return answer("none", None, 1)
        rest = whole_steps(t_off, dt) * dt

        def wide(ok: int, fail: int) -> bool:
            """Whether the bracket is wider than asked (in t_on or in duty cycle)."""
            low, high = (n * dt / (n * dt + rest) for n in (ok, fail))
            return fail - ok > tolerance_steps or high - low > precision * low

        ok, fail = 1, steps
        while fail - ok > 1 and wide(ok, fail):
            middle = (ok + fail) // 2
            reached = trial(middle)
            if reached is None:
                return answer("interrupted", ok, fail)
            ok, fail = (ok, middle) if reached else (middle, fail)
        return answer("bracketed", ok, fail)


def _effort(result: SimulationResult) -> Effort | None:
    """The most loaded group on the run's first hold step (None: no hold step)."""
    held = [k for k, phase in enumerate(result.timeline.phase) if phase == "hold"]
    if not held:
        return None
    loads = result.timeline.load[held[0]]
    group = int(np.argmax([tied(load) for load in loads]))
    half = result.problem.body.half_joints[group]
    return Effort(half.name, half.region, float(loads[group]))


def duty_cycles(
    problem: Problem,
    t_off_s: Sequence[float],
    *,
    horizon_s: float | None = None,
    tolerance_s: float | None = None,
    precision: float = DEFAULT_PRECISION,
    solver: str | None = None,
) -> list[DutyCycle]:
    """``duty_cycle`` for each rest time [s], stopping after one that Ctrl-C cut short."""
    out = []
    for rest in t_off_s:
        out.append(
            duty_cycle(
                problem,
                rest,
                horizon_s=horizon_s,
                tolerance_s=tolerance_s,
                precision=precision,
                solver=solver,
            )
        )
        if out[-1].verdict == "interrupted":
            break
    return out


def table_columns(cycles: Sequence[DutyCycle]) -> dict[str, list[Any]]:
    """One row per rest time: the columns of duty_cycle.csv (times in s, duty cycle in %)."""
    return {
        "t_off_s": [c.t_off_s for c in cycles],
        "rest_s": [c.rest_s for c in cycles],
        "verdict": [c.verdict for c in cycles],
        "sustainable_t_on_s": [c.sustainable_t_on_s for c in cycles],
        "failing_t_on_s": [c.failing_t_on_s for c in cycles],
        "duty_cycle_pct": [c.duty_cycle_pct for c in cycles],
        "failing_duty_cycle_pct": [
            None if c.duty_cycle_bracket_pct is None else c.duty_cycle_bracket_pct[1]
            for c in cycles
        ],
        "effort_group": [None if c.effort is None else c.effort.half_joint for c in cycles],
        "effort_pct_mvc": [None if c.effort is None else c.effort.load_pct_mvc for c in cycles],
        "potvin_duty_cycle_pct": [_guide(c, "acceptable_duty_cycle_pct") for c in cycles],
        "potvin_effort_at_duty_cycle_pct_mvc": [
            _guide(c, "acceptable_effort_at_duty_cycle_pct_mvc") for c in cycles
        ],
        "horizon_s": [c.horizon_s for c in cycles],
        "tolerance_s": [c.tolerance_s for c in cycles],
        "simulations": [len(c.trials) for c in cycles],
        "wall_time_s": [c.wall_time_s for c in cycles],
        "flags": ["; ".join(c.flags) for c in cycles],
    }


def _guide(cycle: DutyCycle, key: str) -> float | None:
    guideline = cycle.guideline()
    return None if guideline is None else guideline[key]


def write_duty_cycles(cycles: Sequence[DutyCycle], out: Path) -> list[Path]:
    """Into ``out``: duty_cycle.json (every search and its trials), duty_cycle.csv (one row
    per rest time), duty_cycle.png (the fatigue of the runs at each end of the bracket
    of the first search that found one: its first cycles, rests shaded, and each cycle's peak
    and trough over the horizon) and, for more than one rest time,
    duty_cycle_vs_t_off.png."""
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "duty_cycle.json", out / "duty_cycle.csv"]
    paths[0].write_text(dumps([c.summary() for c in cycles]) + "\n")
    write_table(table_columns(cycles), paths[1])
    from casadi_posture.output.schedule_plots import (  # imported when drawn
        plot_duty_vs_rest,
        plot_runs,
    )

    shown = next((c for c in cycles if c.verdict == "bracketed"), cycles[0] if cycles else None)
    if shown is not None and shown.runs:
        labelled = [
            (
                f"{'Sustainable' if label == 'stays below' else 'Not sustainable'}: "
                f"{_cycle(result)}, {label} the threshold{_when(result, shown)}",
                result,
            )
            for label, result in shown.runs.items()
        ]
        paths.append(plot_runs(labelled, out / "duty_cycle.png"))
    if len(cycles) > 1:
        heading = f"{Path(cycles[0].problem).stem}: over {span(cycles[0].horizon_s)}"
        paths.append(
            plot_duty_vs_rest(
                [c.rest_s for c in cycles],
                [c.sustainable_t_on_s if c.verdict != "none" else None for c in cycles],
                [c.failing_t_on_s for c in cycles],
                cycles[0].horizon_s,
                heading,
                out / "duty_cycle_vs_t_off.png",
            )
        )
    return paths


def span(horizon_s: float) -> str:
    """A horizon [s] in words, always with its seconds: ``an 8-h shift (28800 s)``,
    ``30 min (1800 s)``, ``90 s``."""
    if horizon_s == SHIFT_S:
        return f"an 8-h shift ({horizon_s:g} s)"
    for unit, size in (("h", 3600.0), ("min", 60.0)):
        if horizon_s >= size and horizon_s % size == 0:
            return f"{horizon_s / size:g} {unit} ({horizon_s:g} s)"
    return f"{horizon_s:g} s"


def _cycle(result: SimulationResult) -> str:
    """``88 s on per 118 s cycle (74.6 % duty cycle)``: a trial's schedule on its step grid."""
    schedule = result.schedule
    if schedule is None or "rest" not in result.timeline.phase:
        return "held continuously"
    on, cycle = schedule.hold_steps * schedule.dt_s, schedule.period_steps * schedule.dt_s
    return f"{on:g} s on per {cycle:g} s cycle ({100 * on / cycle:.1f} % duty cycle)"


def _when(result: SimulationResult, cycle: DutyCycle) -> str:
    """`` at 11.7 min (the trial stops there)`` for a trial that reached the threshold, ``
    over an 8-h shift (28800 s)`` for one that did not."""
    if result.stop != "fatigue_threshold":
        return f" over {span(cycle.horizon_s)}"
    return f" at {result.timeline.time[-1] / 60:.1f} min (the trial stops there)"
