"""The solved posture as a function of the inputs, by the implicit function theorem on the
optimality conditions the IK's answer satisfies (docs/sensitivity.md).

With its levels achieved (residual at most ``ACHIEVED_TOLERANCE``) kept as equalities
``c(q, θ) = 0``, at most one level not achieved minimised, ``f = ½‖e(q, θ)‖²``, and the
DOFs at a joint limit held there, the prioritized IK's answer is a stationary point of

    L(z, λ, θ) = f + λᵀ Pᵀc,    F(z, λ, θ) = (∇_z L, Pᵀc) = 0,

z the free DOFs, P per level an orthonormal basis of the range of its Jacobian within the
motions the levels above leave free, at the answer (a row a level cannot move is settled by
the levels above: the lateral row of a sagittal arm's position task, the height of a dot on a
horizontal line of higher priority). The
answer is polished by (Gauss-)Newton steps on F, then dz/dθ solves ∂F/∂(z, λ)·dx =
−∂F/∂θ (more equations than unknowns where levels below the minimised one are kept: the
system is consistent, and solved by least squares; it must have full column rank).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from casadi_posture.ik.result import ACTIVE_TOLERANCE
from casadi_posture.sensitivity_analysis.parametric import ParametricProblem

#: Newton's method on the optimality conditions stops at this ‖F‖ or after this many steps.
POLISH_TOLERANCE = 1e-12
POLISH_STEPS = 20
#: ∂F/∂(z, λ) is singular (the tasks leave the posture free) below this relative
#: singular value; rows of ∂c/∂z below it (relative to the largest) are dropped.
SINGULAR = 1e-10


@dataclass(frozen=True)
class PostureDerivative:
    """The polished posture ``q`` [rad] and ``dq`` = dq/dθ [rad per input unit] (None: the
    tasks do not determine the posture, ``note`` says why); ``held`` the DOFs at a joint
    limit; ``kept`` the levels held as equalities, ``minimised`` the level minimised (1-based,
    None: every level achieved); ``stationarity`` ‖F‖ at ``q``."""

    q: np.ndarray
    dq: np.ndarray | None
    held: tuple[str, ...]
    kept: tuple[int, ...]
    minimised: int | None
    stationarity: float
    note: str = ""


def posture_derivative(
    graph: ParametricProblem, q0: np.ndarray, achieved: Sequence[bool]
) -> PostureDerivative:
    """Polish the IK's answer ``q0`` [rad] (levels ``achieved`` as the solver found them) and
    differentiate it with respect to ``graph.theta`` at ``graph.values``."""
    body, n = graph.body, graph.body.n
    missed = [k for k, ok in enumerate(achieved) if not ok]
    kept = tuple(k + 1 for k, ok in enumerate(achieved) if ok)
    minimised = missed[0] if missed else None
    if len(missed) > 1:
        note = (
            f"levels {', '.join(str(k + 1) for k in missed)} are not achieved: the posture's "
            "derivative needs every level but one achieved"
        )
        return PostureDerivative(q0, None, (), kept, None, float("nan"), note)
    at_limit = (q0 <= body.lower + ACTIVE_TOLERANCE) | (q0 >= body.upper - ACTIVE_TOLERANCE)
    held = tuple(d.name for d, a in zip(body.dofs, at_limit, strict=True) if a)
    free = np.flatnonzero(~at_limit)
    z = ca.SX.sym("z", free.size)
    q_of_z = ca.SX(q0)
    for j, i in enumerate(free):
        q_of_z[int(i)] = z[j]
    theta, values = graph.theta, graph.values

    residuals = [ca.substitute(e, graph.q, q_of_z) for e in graph.levels]
    jacobians = ca.Function("dc", [z, theta], [ca.jacobian(e, z) for e in residuals])
    bases = _level_bases(
        [np.asarray(j) for j in jacobians.call([q0[free], values])], free.size, minimised
    )
    reduced = [ca.mtimes(ca.DM(b.T), e) for b, e in zip(bases, residuals, strict=True)]
    above = ca.vertcat(ca.SX(0, 1), *reduced[: minimised if minimised is not None else 0])
    equations = [r for k, r in enumerate(reduced) if k != minimised]
    unknowns = z
    if minimised is not None:
        multipliers = ca.SX.sym("lambda", above.numel())
        lagrangian = 0.5 * ca.sumsqr(residuals[minimised]) + ca.dot(multipliers, above)
        equations.append(ca.gradient(lagrangian, z))
        unknowns = ca.vertcat(z, multipliers)
    conditions = ca.vertcat(ca.SX(0, 1), *equations)
    kkt = ca.Function(
        "kkt",
        [unknowns, theta],
        [conditions, ca.jacobian(conditions, unknowns), ca.jacobian(conditions, theta)],
    )
    start = _multipliers(kkt, q0[free], unknowns.numel() - free.size, values)
    x_value, residual = _polish(kkt, start, values)
    q = q0.copy()
    q[free] = x_value[: free.size]
    level = None if minimised is None else minimised + 1
    _, k_matrix, b_matrix = (np.asarray(v) for v in kkt(x_value, values))
    singular = np.linalg.svd(k_matrix, compute_uv=False) if k_matrix.size else np.ones(1)
    if k_matrix.shape[0] < k_matrix.shape[1] or singular.min() <= SINGULAR * max(
        singular.max(), 1.0
    ):
        note = (
            "the tasks leave the posture free (the optimality conditions do not determine "
            "it): give a posture task at the lowest level to determine it"
        )
        return PostureDerivative(q, None, held, kept, level, residual, note)
    dx = -np.linalg.lstsq(k_matrix, b_matrix, rcond=None)[0]
    dq = np.zeros((n, values.size))
    dq[free] = dx[: free.size]
    return PostureDerivative(q, dq, held, kept, level, residual)


def _level_bases(
    jacobians: Sequence[np.ndarray], n: int, minimised: int | None
) -> list[np.ndarray]:
    """Per level (in priority order), orthonormal columns spanning what the level can still
    change: the range of its Jacobian restricted to the motions the levels above leave free
    (rows a lower level cannot move are settled by the levels above). The minimised level
    takes the motions its Gauss-Newton Hessian sees; those it leaves flat go on down."""
    free = np.eye(n)
    bases = []
    for k, jacobian in enumerate(jacobians):
        jacobian = jacobian.reshape(-1, n)
        if jacobian.shape[0] == 0 or free.shape[1] == 0:
            bases.append(np.zeros((jacobian.shape[0], 0)))
            continue
        u, s, vt = np.linalg.svd(jacobian @ free, full_matrices=True)
        rank = int(np.sum(s > SINGULAR * max(float(np.max(np.abs(jacobian))), 1.0)))
        bases.append(u[:, :rank] if k != minimised else np.eye(jacobian.shape[0]))
        free = free @ vt[rank:].T
    return bases


def _multipliers(kkt: ca.Function, z: np.ndarray, m: int, theta: np.ndarray) -> np.ndarray:
    """(z, λ) with λ the least-squares multipliers of the stationarity rows (the last n rows
    of the conditions) at ``z``."""
    x = np.concatenate([z, np.zeros(m)])
    if m == 0:
        return x
    conditions, k_matrix, _ = (np.asarray(v) for v in kkt(x, theta))
    gradient = conditions[-z.size :].ravel()
    lam = np.linalg.lstsq(k_matrix[-z.size :, z.size :], -gradient, rcond=None)[0]
    return np.concatenate([z, lam])


def _polish(kkt: ca.Function, x: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, float]:
    """Newton's method on the optimality conditions from ``x``; the point and ‖F‖ there."""
    best = x.copy()
    conditions = np.asarray(kkt(x, theta)[0]).ravel()
    norm = float(np.linalg.norm(conditions))
    for _ in range(POLISH_STEPS):
        if norm <= POLISH_TOLERANCE:
            break
        k_matrix = np.asarray(kkt(x, theta)[1])
        step = np.linalg.lstsq(k_matrix, -conditions, rcond=None)[0]
        trial = x + step
        trial_conditions = np.asarray(kkt(trial, theta)[0]).ravel()
        trial_norm = float(np.linalg.norm(trial_conditions))
        if not trial_norm < norm:
            break
        x, conditions, norm = trial, trial_conditions, trial_norm
        best = x.copy()
    return best, norm
