"""The design entry point: the start (the IK at the file's design), the NLP from one or
several starts, and the best design's answer with its re-solve check (docs/design.md)."""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from casadi_posture import static
from casadi_posture.biomech.low_back import LUMBAR, has_lumbar_joint
from casadi_posture.body.loads import pack
from casadi_posture.errors import CasadiPostureError, ProblemError
from casadi_posture.ik.result import ACHIEVED_TOLERANCE
from casadi_posture.problem import Problem, problem_from_data
from casadi_posture.workplace_design.answer import Design
from casadi_posture.workplace_design.nlp import design_nlp, endurance_threshold
from casadi_posture.workplace_design.objectives import (
    OBJECTIVES,
    Score,
    format_score,
    is_better,
    score,
    scores_agree,
)
from casadi_posture.workplace_design.quantities import Free, as_overrides, free_quantities

#: A load at most this far above T_0 [%MVC] counts as clamped (not limiting) at the optimum.
CLAMP_MARGIN_PCT_MVC = 1e-3


@dataclass(frozen=True)
class _Start:
    """What the design starts from: the IK's answer at the file's design, its objective and
    the priority levels kept as equalities and dropped."""

    problem: Problem
    objective: str
    free: tuple[Free, ...]
    answer: static.StaticAnswer
    score: Score
    kept: tuple[int, ...]


def spread(count: int, dims: int) -> np.ndarray:
    """``count − 1`` points of the unit box [0, 1]^dims, one row each: the Hammersley set
    of ``count`` points without its origin. The first coordinate is evenly spaced (i/count:
    one free key gets evenly spaced starts); the others are the radical inverses of i in
    the primes 2, 3, 5, ..., so that the points fill the box instead of its diagonal."""
    primes: list[int] = []
    candidate = 2
    while len(primes) < dims - 1:
        if all(candidate % q for q in primes):
            primes.append(candidate)
        candidate += 1

    def radical_inverse(i: int, base: int) -> float:
        value, scale = 0.0, 1.0 / base
        while i:
            i, digit = divmod(i, base)
            value += digit * scale
            scale /= base
        return value

    rows = [[i / count, *(radical_inverse(i, b) for b in primes)] for i in range(1, count)]
    return np.array(rows, dtype=float).reshape(count - 1, dims)


def design(
    problem: Problem,
    free: Mapping[str, tuple[float, float]],
    objective: str = "endurance",
    keep_levels: int | None = None,
    starts: int = 1,
) -> Design:
    """Choose the ``free`` quantities ({KEY or KEY1,KEY2: (LO, HI)} [m]) to maximise
    ``objective`` (one of ``OBJECTIVES``; the compression is minimised, with the lumbar
    bending and rotation held at the start's) by the design NLP, and check the answer by
    re-solving the IK with the file's solver at the best design. The levels the IK achieves
    at the start are kept as equalities, only the first ``keep_levels`` of them if given
    (a posture task the start happens to achieve would otherwise fix the posture).
    ``starts`` > 1 also starts the NLP from the IK at ``starts − 1`` designs spread over
    the bounds (``spread``; a local method: the best answer is kept)."""
    if starts < 1:
        raise ProblemError(problem.path, "--starts", starts, "a number of starts ≥ 1")
    if objective not in OBJECTIVES:
        raise ProblemError(problem.path, "--objective", objective, f"one of {list(OBJECTIVES)}")
    hierarchy = problem.hierarchy()
    if keep_levels is not None and not 1 <= keep_levels <= hierarchy.depth:
        expected = f"a number of levels from 1 to {hierarchy.depth}"
        raise ProblemError(problem.path, "--keep-levels", keep_levels, expected)
    quantities = tuple(free_quantities(problem, hierarchy, free))
    if objective == "endurance":
        endurance_threshold(problem)
    if objective == "compression" and not has_lumbar_joint(problem.body):
        expected = (
            f"a body with a lumbar joint (a {LUMBAR[0]} DOF) for the L5/S1 compression; "
            f"body {problem.body.name!r} has none: use endurance or capable-male/female"
        )
        raise ProblemError(problem.path, "--objective", objective, expected)
    answer = static.solve(problem)
    if not answer.reached:
        raise CasadiPostureError(
            f"{problem.path}: level 1 is not achieved at the start design "
            f"({answer.flags[0] if answer.flags else 'no detail'}); a design "
            "starts from a feasible posture"
        )
    depth = hierarchy.depth if keep_levels is None else keep_levels
    kept = tuple(k for k, lv in enumerate(answer.levels) if lv.achieved and k < depth)
    start = _Start(problem, objective, quantities, answer, score(answer, objective), kept)
    notes = [static.SCHEDULE_NOTE] if problem.spec.schedule is not None else []
    dropped = [lv for lv in answer.levels if lv.level - 1 not in kept]
    if dropped:
        reasons = {True: "above --keep-levels", False: "not achieved at the start"}
        why = ", ".join(f"{lv.level} ({lv.tasks}, {reasons[lv.achieved]})" for lv in dropped)
        notes.append(
            f"levels dropped: {why}; the person takes whichever posture is best for the objective"
        )
    q0 = answer.torques.q
    d0 = np.array([f.start_m for f in quantities])
    if objective == "endurance" and math.isinf(start.score.value):
        notes.append(
            "every group is at or below T_0 at the start: the task is unlimited already, "
            "nothing to maximise (the start is the design)"
        )
        return _finish(start, d0, q0, _Run("not run (unlimited at the start)"), notes, [])
    params = np.concatenate([hierarchy.targets, pack(problem.loads)])
    nlp = design_nlp(problem, hierarchy, kept, quantities, objective, (q0, d0, params))
    if nlp.redundant:
        notes.append(
            f"{nlp.redundant} rows of the kept levels repeat others at the start (their "
            "gradients are combinations of higher rows) and were left out of the NLP; every "
            "kept level's residual is checked at the answer"
        )
    if nlp.equalities >= problem.body.n + len(quantities):
        notes.append(
            f"the kept levels fix the posture and the design ({nlp.equalities} independent "
            f"equations on {problem.body.n} joints and {len(quantities)} design values): "
            "nothing to choose; drop a level with --keep-levels to let the body move"
        )
        return _finish(start, d0, q0, _Run("not run (no freedom)"), notes, [])
    lower = np.array([f.lower_m for f in quantities])
    upper = np.array([f.upper_m for f in quantities])
    points = [(q0, d0)]
    for fraction in spread(starts, len(quantities)):
        d_i = lower + (upper - lower) * fraction
        at = problem_from_data(problem.data, problem.path, as_overrides(quantities, d_i))
        other = static.solve(at)
        if all(other.levels[k].achieved for k in kept):
            points.append((other.torques.q, d_i))
    if starts > 1:
        notes.append(
            f"{len(points)} starts (the file's design and {len(points) - 1} of {starts - 1} "
            "designs spread over the bounds whose IK keeps the task); the best answer is "
            "reported"
        )
    body = problem.body
    joints_lower, joints_upper = body.lower, body.upper
    if objective == "compression":
        held = [body.index[name] for name in LUMBAR[1:] if name in body.index]
        joints_lower[held] = joints_upper[held] = q0[held]
        shown = ", ".join(
            f"{body.dof_names[i]} {round(math.degrees(q0[i]), 1) + 0.0:g}°" for i in held
        )
        notes.append(
            f"trunk held as at the start ({shown}): the sagittal model leaves out the lateral "
            "and twisting moments, and the NLP would bend and twist the trunk to hide the "
            "load from it"
        )
    lbx = np.concatenate([joints_lower, lower, [-np.inf]])
    ubx = np.concatenate([joints_upper, upper, [np.inf]])
    lbg, ubg = nlp.constraint_bounds()
    best: tuple[float, _Run, np.ndarray] | None = None
    for q_i, d_i in points:
        t0 = float(nlp.objective(q_i, params))
        began = time.perf_counter()
        out = nlp.solver(
            x0=np.concatenate([q_i, d_i, [t0]]), p=params, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg
        )
        wall = time.perf_counter() - began
        stats = nlp.solver.stats()
        run = _Run(str(stats["return_status"]), bool(stats["success"]), stats["iter_count"], wall)
        x = np.asarray(out["x"]).ravel()
        rank = (run.success, float(x[-1]))
        if best is None or rank > (best[1].success, best[0]):
            best = (float(x[-1]), run, x)
    assert best is not None
    _, run, x = best
    q = np.clip(x[: body.n], body.lower, body.upper)
    d = np.clip(x[body.n : body.n + len(quantities)], lower, upper)
    flags = [] if run.success else [f"IPOPT failed: {run.status}"]
    return _finish(start, d, q, run, notes, flags)


@dataclass(frozen=True)
class _Run:
    """IPOPT's outcome: its status word, success, iterations and wall time [s]."""

    status: str
    success: bool = True
    iterations: int = 0
    wall_time_s: float = 0.0


def _finish(
    start: _Start, d: np.ndarray, q: np.ndarray, run: _Run, notes: list[str], flags: list[str]
) -> Design:
    """The best design's answer at the NLP's posture ``q`` [rad] and values ``d`` [m], the
    re-solve check and their notes."""
    problem, objective, kept = start.problem, start.objective, start.kept
    at_best = problem_from_data(problem.data, problem.path, as_overrides(start.free, d))
    best_answer = static.at_posture(at_best, q)
    best = score(best_answer, objective)
    residuals = at_best.hierarchy().residual_norms(q)
    kept_residual = max((float(residuals[k]) for k in kept), default=0.0)
    if kept_residual > ACHIEVED_TOLERANCE:
        flags.append(
            f"the NLP's posture leaves a kept level at {kept_residual:.3g} "
            f"(> {ACHIEVED_TOLERANCE:g}): the design does not keep the task"
        )
    if is_better(start.score, best, objective) and run.success:
        flags.append("the NLP ended worse than the start's objective (a local method left it)")
    check_answer = static.solve(at_best)
    check = score(check_answer, objective)
    gap = float(np.degrees(np.max(np.abs(check_answer.torques.q - q))))
    agrees = scores_agree(best, check, objective)
    lost = [lv.level for lv in check_answer.levels if lv.level - 1 in kept and not lv.achieved]
    if lost:
        flags.append(f"the re-solved IK does not achieve kept level(s) {lost} at the design")
    if not agrees:
        gain = "reduction" if objective == "compression" else "gain"
        flags.append(
            f"the re-solved IK ({check_answer.ik.solver if check_answer.ik else '-'}) gives "
            f"{format_score(check.value, objective)} where the NLP gives "
            f"{format_score(best.value, objective)}: "
            f"it settles the posture its own way (largest joint difference {gap:.1f} deg), "
            "with the dropped levels pulling it, while the NLP takes the posture best for the "
            f"objective among those that keep the task; the {gain} is the re-solve's, and the "
            "NLP's posture is not what the IK predicts a person does at the design"
        )
    if objective == "endurance" and best.load_pct_mvc is not None and math.isfinite(best.value):
        threshold = float(problem.fatigue.settings()["load_threshold_pct_mvc"])
        if best.load_pct_mvc <= threshold + CLAMP_MARGIN_PCT_MVC:
            flags.append(
                "the limiting group sits at T_0 at the optimum: the clamp, not the group's "
                "endurance, bounded the objective"
            )
    levels = start.answer.levels
    return Design(
        problem=problem,
        objective=objective,
        free=start.free,
        best_m=tuple(float(v) for v in d),
        start=start.score,
        best=best,
        check=check,
        start_answer=start.answer,
        best_answer=best_answer,
        check_answer=check_answer,
        kept=tuple(f"{levels[k].level}: {levels[k].tasks}" for k in kept),
        dropped=tuple(f"{lv.level}: {lv.tasks}" for lv in levels if lv.level - 1 not in kept),
        status=run.status,
        success=run.success,
        iterations=run.iterations,
        wall_time_s=run.wall_time_s,
        kept_residual=kept_residual,
        posture_gap_deg=gap,
        agrees=agrees,
        notes=tuple(notes),
        flags=tuple(flags + list(best_answer.flags)),
    )
