"""The design NLP over the posture and the design together (docs/design.md).

Variables: the posture q [rad] within the joint limits, the design d [m] within its bounds
and the epigraph variable t. Constraints: every priority level the IK achieves at the start
design is kept as an equality e_k(q, p(d)) = 0 (the others, typically the lowest posture
task, are dropped: the person takes whichever posture is best). Objective, maximise t with

- ``endurance``: ``log E_g(max(L_g, T_0)) ≥ t`` for every half-joint g, with
  ``L_g = 100·σ_g·τa_j(q)/st_g(q)`` [%MVC] (σ = +1 for the positive group, −1 for the
  negative) and ``E_g`` the fatigue model's endurance [s]; clamped at the load threshold
  T_0, a group at or below it never binds ("unlimited below T_0"); and ``L_g ≤ 100 %MVC``;
- ``capable-male`` / ``capable-female``: ``(μ_g − max(τ_g, 0))/s_g ≥ t`` with μ_g, s_g the
  population strength's mean and SD [N·m] of that sex (biomech/capability.py): Φ is
  monotone, so the largest smallest z-score is the largest share capable;
- ``compression``: ``−C_m(q) ≥ t`` [N] for each muscle m of the L5/S1 compression
  C = −F·e_z + max(M_s/E, −M_s/A) of biomech/low_back.py (its CasADi expressions):
  C_e = −F·e_z + M_s/E (erector spinae), C_a = −F·e_z − M_s/A (rectus abdominis), so that
  the largest t is −C without the kink of the max at M_s = 0; the lumbar bending and
  rotation are held at the start's (the model leaves out the moments they would hide the
  load in).

The NLP starts from the IK's posture at the start design, which is feasible, and is built
once per problem structure (the targets, loads and bounds are its parameters). The answer
is checked by re-solving the IK with the problem file's solver at the design.
"""

from __future__ import annotations

import hashlib
import math
import threading
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from casadi_posture import static
from casadi_posture.biomech.endurance import numeric
from casadi_posture.biomech.low_back import OUTPUTS, low_back_expressions, moment_arms
from casadi_posture.errors import ProblemError
from casadi_posture.ik.hierarchy import TaskHierarchy
from casadi_posture.problem import Problem
from casadi_posture.workplace_design.objectives import sex_of
from casadi_posture.workplace_design.quantities import Free

#: The low-back outputs the compression objective's measures are made of.
_COMPRESSION_TERMS = ("compression", "sagittal_moment", "muscle_force")


@dataclass(frozen=True)
class _Nlp:
    """The compiled design NLP of one problem structure and its sizes."""

    solver: ca.Function
    objective: ca.Function
    equalities: int
    redundant: int
    groups: int
    limits: int

    def constraint_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """lbg, ubg: the kept levels = 0, the epigraph rows ≥ 0, the load limits ≤ 0."""
        zeros, inf = np.zeros, np.full
        lbg = np.concatenate(
            [zeros(self.equalities), zeros(self.groups), inf(self.limits, -np.inf)]
        )
        ubg = np.concatenate([zeros(self.equalities), inf(self.groups, np.inf), zeros(self.limits)])
        return lbg, ubg


_cache = threading.local()

#: Design NLPs a thread keeps (one per problem structure, kept levels and free keys).
CACHED_STRUCTURES = 4

#: IPOPT's iteration limit for the design NLP.
MAX_ITERATIONS = 1000


def design_nlp(
    problem: Problem,
    hierarchy: TaskHierarchy,
    kept: Sequence[int],
    free: Sequence[Free],
    objective: str,
    start: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> _Nlp:
    """The design NLP (module docstring) with x = [q, d, t] and parameters [targets, loads],
    built once per structure in this thread (keyed by the SHA-256 of its functions).

    The kept levels' rows are taken in priority order, and a row whose gradient in (q, d)
    at the ``start`` (q [rad], d [m], parameters) is a combination of those before it is
    left out: an achieved posture task on the joints the feet already fix, a dot on the
    line it lies on, would make IPOPT's equality Jacobian rank-deficient (more equalities
    than variables). The others imply it near the start (constant rank); the residual of
    every kept level is checked at the answer."""
    body, torques = problem.body, problem.torque_model()
    q, d, t = body.q, ca.SX.sym("d", len(free)), ca.SX.sym("t")
    base = ca.SX.sym("targets", hierarchy.p.numel())
    p = ca.SX(base)
    for j, quantity in enumerate(free):
        for index in quantity.indices:
            p[index] = d[j]
    residual = ca.substitute(ca.vertcat(*[hierarchy.residuals[k] for k in kept]), hierarchy.p, p)
    qd = ca.vertcat(q, d)
    params = ca.vertcat(base, torques.p)
    gradient = ca.Function("gradient", [qd, params], [ca.jacobian(residual, qd)])
    q0, d0, p0 = start
    rows = independent_rows(np.asarray(gradient(np.concatenate([q0, d0]), p0)))
    equalities = residual[rows] if rows else ca.SX(0, 1)
    measures, limits = _measures(problem, torques, objective)
    x = ca.vertcat(q, d, t)
    g = ca.vertcat(equalities, measures - t, limits)
    nlp = {"x": x, "p": params, "f": -t, "g": g}
    key = hashlib.sha256(
        ca.Function("design", [x, params], [-t, g]).serialize().encode()
    ).hexdigest()
    if not hasattr(_cache, "nlps"):
        _cache.nlps = OrderedDict()
    nlps: OrderedDict = _cache.nlps
    if key not in nlps:
        ipopt = {
            "print_level": 0,
            "sb": "yes",
            "max_iter": MAX_ITERATIONS,
            "tol": 1e-8,
            # limited-memory for a row per group (on the standing shelf the exact Hessian was
            # slower and stopped lower), exact for the compression's two rows (the
            # limited-memory one ran out of iterations at fixed shelf heights)
            "hessian_approximation": "exact" if objective == "compression" else "limited-memory",
        }
        options = {"print_time": False, "error_on_fail": False, "ipopt": ipopt}
        nlps[key] = ca.nlpsol("design", "ipopt", nlp, options)
        while len(nlps) > CACHED_STRUCTURES:
            nlps.popitem(last=False)
    nlps.move_to_end(key)
    value = ca.Function("measure", [q, params], [ca.mmin(measures)])
    return _Nlp(
        nlps[key], value, len(rows), residual.numel() - len(rows), measures.numel(), limits.numel()
    )


def independent_rows(jacobian: np.ndarray, tolerance: float = 1e-9) -> list[int]:
    """Indices of the rows of ``jacobian`` that are not combinations of the rows before them
    (Gram-Schmidt, twice, with a relative ``tolerance``); a zero row is never kept."""
    basis: list[np.ndarray] = []
    rows = []
    for r, row in enumerate(jacobian):
        v = row.astype(float)
        for _ in range(2):
            for b in basis:
                v = v - b.dot(v) * b
        if np.linalg.norm(v) > tolerance * max(1.0, float(np.linalg.norm(row))):
            basis.append(v / np.linalg.norm(v))
            rows.append(r)
    return rows


def _measures(problem: Problem, torques: Any, objective: str) -> tuple[ca.SX, ca.SX]:
    """The epigraph's measures — per half-joint the log-endurance [log s] or z-score [-],
    or per back muscle −compression [N] — and the extra inequalities ``L_g − 100 ≤ 0`` [%MVC]
    (endurance only), all in ``body.q`` and the load vector ``torques.p``."""
    body = problem.body
    if objective == "compression":
        extensor, flexor = moment_arms()
        back = low_back_expressions(body, problem.loads, torques.p, extensor, flexor)
        compression, moment, muscle = (back[OUTPUTS.index(k)] for k in _COMPRESSION_TERMS)
        axial = compression - muscle  # −F·e_z [N], smooth
        # muscle = max(M, 0)/E + max(−M, 0)/A = max(M/E, −M/A): a row per muscle, smooth
        rows = ca.vertcat(axial + moment / extensor, axial - moment / flexor)
        return -rows, ca.SX(0, 1)
    active = [torques.tau_act[h.dof_index] * h.sign for h in body.half_joints]
    strength = [torques.strength[k] for k in range(len(body.half_joints))]
    if objective == "endurance":
        threshold = endurance_threshold(problem)
        load = [100.0 * a / s for a, s in zip(active, strength, strict=True)]
        measure = [
            ca.log(problem.fatigue.endurance_expression(ca.fmax(L, threshold), h.region, numeric))
            for L, h in zip(load, body.half_joints, strict=True)
        ]
        return ca.vertcat(*measure), ca.vertcat(*load) - 100.0
    sex = sex_of(objective)
    # population_strength() is affine in the strength it is given (a group the file sets takes the
    # problem's strength as its mean, SD = CV × mean; the others are constant): its value at
    # strengths 0 and 1 gives each group's mean and SD as expressions of st_g(q).
    zero = static.population_strength(problem, np.zeros(len(strength)))
    one = static.population_strength(problem, np.ones(len(strength)))
    measure = []
    for a, s, g0, g1 in zip(active, strength, zero, one, strict=True):
        mean = g0.mean[sex] + (g1.mean[sex] - g0.mean[sex]) * s
        sd = g0.sd[sex] + (g1.sd[sex] - g0.sd[sex]) * s
        measure.append((mean - ca.fmax(a, 0.0)) / sd)
    return ca.vertcat(*measure), ca.SX(0, 1)


def endurance_threshold(problem: Problem) -> float:
    """T_0 [%MVC] of the endurance objective, refused where the clamp cannot work: the 3CC
    law (no expression), T_0 ≤ 0, or an endurance not finite at T_0."""
    settings = problem.fatigue.settings()
    law = settings["recovery_law"]
    probe = ca.SX.sym("load")
    regions = dict.fromkeys(h.region for h in problem.body.half_joints)
    if any(problem.fatigue.endurance_expression(probe, r, numeric) is None for r in regions):
        expected = (
            "threshold or continuous for --objective endurance (the 3cc_r endurance is found "
            "by time stepping: no gradient); --objective capable-male or capable-female "
            "works with any law"
        )
        raise ProblemError(problem.path, "fatigue.recovery_law", law, expected)
    threshold = float(settings["load_threshold_pct_mvc"])
    if not threshold > 0:
        expected = (
            "T_0 > 0 %MVC for --objective endurance (a group that carries nothing has no "
            "finite endurance to clamp at T_0)"
        )
        raise ProblemError(problem.path, "fatigue.load_threshold_pct_mvc", threshold, expected)
    for region in regions:
        seconds = float(problem.fatigue.endurance_expression(ca.DM(threshold), region, numeric))
        if not (math.isfinite(seconds) and seconds > 0):
            expected = (
                f"a law whose endurance at T_0 is finite (region {region}: {seconds} s); "
                "use --objective capable-male or capable-female"
            )
            raise ProblemError(problem.path, "fatigue.recovery_law", law, expected)
    return threshold
