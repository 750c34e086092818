"""Strict priorities as a sequence of NLPs solved with IPOPT (docs/model.md).

Level k solves

    min_q ‖e_k(q)‖²
    s.t.  q_min ≤ q ≤ q_max,   aᵀq ≤ b,   S_j (e_j(q) - e_j*) = 0   for j < k

and, when the levels leave joint space redundant, one more level minimises
‖q - q_prev‖² with every task level kept, so the posture is unique. (Adding
ε‖q - q_prev‖² to every level instead biases each task by about
ε·Δq/σ² and, with ε small enough not to matter, leaves IPOPT crawling along the
solution set at "acceptable" accuracy: 7e-8 m of residual measured on the
holding problems with ε = 1e-10.)

Higher levels are kept as residual *vectors* (never the scalar ‖e_j‖², whose
constraint qualification fails at a zero residual). Only the rows a level can
still change are kept: S_j holds the left singular vectors of J_j P_{j-1} at
level j's solution (P_{j-1} the projector onto the nullspace of the higher
levels and of the active bounds and inequality), padded with zero rows whose
bounds are infinite, so every NLP has a fixed shape and is built once. The
returned posture is re-checked against the bounds, the inequality and the kept
residuals with this module's tolerances; IPOPT's word alone is not trusted.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from casadi_posture.ik.hierarchy import Inequality, TaskHierarchy
from casadi_posture.ik.result import ACTIVE_TOLERANCE, IKResult, active_constraints

#: Re-check tolerances on the returned posture: bounds [rad], aᵀq - b [rad], kept rows
#: of the higher levels' residuals [task units].
BOUND_TOLERANCE = 1e-9
KEPT_RESIDUAL_TOLERANCE = 1e-8


@dataclass(frozen=True)
class LexicographicOptions:
    """Settings of the lexicographic solver: IPOPT ``tolerance`` and ``max_iterations`` per
    level, ``rank_tolerance`` of the kept rows [task units per rad].

    A level whose minimisers form a set (a redundant task) is degenerate for IPOPT: with
    ``tol`` below about 1e-9 it wanders along the set and ends "Solved_To_Acceptable_Level"
    with 1e-8 to 1e-6 m of residual; 1e-8 ends in 7 to 10 iterations at about 4e-9 m
    (measured on the line + plane problem from four starts).
    """

    tolerance: float = 1e-8
    max_iterations: int = 500
    rank_tolerance: float = 1e-9


class LexicographicSolver:
    """One parametric IPOPT NLP per priority level, built once per problem structure."""

    name = "lexicographic"

    def __init__(
        self, hierarchy: TaskHierarchy, options: LexicographicOptions | None = None
    ) -> None:
        self.hierarchy = hierarchy
        self.options = options or LexicographicOptions()
        self.levels = [self._build(k) for k in range(hierarchy.depth + 1)]

    def _build(self, k: int) -> ca.Function:
        """The NLP of level k+1; k = depth is the final ‖q - q_prev‖² level."""
        h, body, opts = self.hierarchy, self.hierarchy.body, self.options
        n, q = body.n, body.q
        q_prev, a, b = ca.SX.sym("q_prev", n), ca.SX.sym("a", n), ca.SX.sym("b")
        params, g = [h.p, q_prev, a, b], [ca.dot(a, q)]
        for j in range(k):
            m = h.sizes[j]
            rows, kept = ca.SX.sym(f"S{j + 1}", m, m), ca.SX.sym(f"e{j + 1}_star", m)
            params += [ca.vec(rows), kept]
            g.append(rows @ (h.residuals[j] - kept))
        f = ca.sumsqr(h.residuals[k]) if k < h.depth else ca.sumsqr(q - q_prev)
        nlp = {"x": q, "p": ca.vertcat(*params), "f": f, "g": ca.vertcat(*g)}
        ipopt = {
            "print_level": 0,
            "sb": "yes",
            "tol": opts.tolerance,
            "max_iter": opts.max_iterations,
            "mu_init": 1e-4,
            "bound_relax_factor": 0.0,
        }
        return ca.nlpsol(
            f"level{k + 1}",
            "ipopt",
            nlp,
            {"expand": True, "print_time": False, "error_on_fail": False, "ipopt": ipopt},
        )

    def solve(self, q0: np.ndarray, inequality: Inequality | None = None) -> IKResult:
        """Solve the levels in order from ``q0`` [rad], each warm-started from the last."""
        start = time.perf_counter()
        h, body = self.hierarchy, self.hierarchy.body
        a = np.zeros(body.n) if inequality is None else np.asarray(inequality.a, dtype=float)
        b = np.inf if inequality is None else float(inequality.b)
        q_prev = np.clip(np.asarray(q0, dtype=float), body.lower, body.upper)
        q, kept, bounds = q_prev.copy(), [], []
        values = h.function(q, h.targets)  # every residual and Jacobian at q, one call
        iterations, solved, status, success = 0, 0, "Solve_Succeeded", True
        redundant = True
        for k, solver in enumerate(self.levels):
            if k == h.depth and not redundant:
                break
            p = np.concatenate(
                [h.targets, q_prev, a, [b if np.isfinite(b) else 1e20]]
                + [v for pair in kept for v in pair]
            )
            lbg = np.concatenate([[-np.inf], *[lo for lo, _ in bounds]])
            ubg = np.concatenate([[b], *[hi for _, hi in bounds]])
            out = solver(x0=q, p=p, lbx=body.lower, ubx=body.upper, lbg=lbg, ubg=ubg)
            stats = solver.stats()
            solved = k + 1
            iterations += int(stats.get("iter_count", 0))
            moved = not self._start_is_better(q, values, out, k, q_prev, inequality)
            problem = ""  # unless moved, the start met every constraint of this level already
            if moved:
                q = np.asarray(out["x"]).reshape(-1)
                problem = self._check(q, np.asarray(out["g"]).reshape(-1), lbg, ubg)
            if not stats["success"] or problem:
                status = f"level {k + 1}: {stats['return_status']}"
                status += f"; {problem}" if problem else ""
                success = False
                break
            if k == h.depth:
                break
            if moved:
                values = h.function(q, h.targets)
            rows, lo, hi, redundant = self._kept_rows(q, values, k, inequality)
            e_k = np.asarray(values[k]).reshape(-1)
            kept.append((rows.ravel(order="F"), e_k))
            bounds.append((lo, hi))
        at_limits, active = active_constraints(body, q, inequality)
        return IKResult(
            self.name,
            q,
            h.residual_norms(q),
            iterations,
            status,
            success,
            at_limits,
            active,
            time.perf_counter() - start,
            solved,
        )

    def _start_is_better(
        self,
        start: np.ndarray,
        values: list,
        out: dict,
        k: int,
        q_prev: np.ndarray,
        inequality: Inequality | None,
    ) -> bool:
        """Whether the level's warm start, feasible, has a smaller objective than IPOPT's
        answer: on a level whose minimisers form a set IPOPT can wander along it and stop
        "acceptable" farther from zero than where it began (1e-6 m from a 9e-8 m start,
        measured on the line + plane problem). The start is feasible for the kept rows by
        construction (they are zero there) and within the bounds; only the inequality is
        checked. ``values``: the hierarchy's residuals and Jacobians at ``start``."""
        if inequality is not None and inequality.a @ start > inequality.b + BOUND_TOLERANCE:
            return False
        h = self.hierarchy
        if k < h.depth:
            objective = float(np.sum(np.asarray(values[k]) ** 2))
        else:
            objective = float(np.sum((start - q_prev) ** 2))
        return objective < float(out["f"])

    def _check(self, q: np.ndarray, g: np.ndarray, lbg: np.ndarray, ubg: np.ndarray) -> str:
        """What the returned posture violates, beyond this module's tolerances ('' if nothing)."""
        body = self.hierarchy.body
        if np.any(q < body.lower - BOUND_TOLERANCE) or np.any(q > body.upper + BOUND_TOLERANCE):
            return "joint limit exceeded"
        if g[0] > ubg[0] + BOUND_TOLERANCE:
            return f"inequality violated by {g[0] - ubg[0]:.3g}"
        excess = np.maximum(g[1:] - ubg[1:], lbg[1:] - g[1:])
        if excess.size and np.max(excess) > KEPT_RESIDUAL_TOLERANCE:
            return f"higher-level residual changed by {np.max(excess):.3g}"
        return ""

    def _kept_rows(
        self, q: np.ndarray, values: list, k: int, inequality: Inequality | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:
        """S_k and its row bounds: the rows of e_k that level k can still change at ``q``
        (``values``: the residuals and Jacobians there); and whether joint space is still
        redundant below level k."""
        h, body = self.hierarchy, self.hierarchy.body
        jacobians = [np.asarray(values[h.depth + j]) for j in range(k + 1)]
        free = np.ones(body.n)
        free[[body.index[d] for d in active_constraints(body, q, None)[0]]] = 0.0
        projector = np.diag(free)
        hard = (
            []
            if inequality is None or inequality.a @ q < inequality.b - ACTIVE_TOLERANCE
            else [inequality.a[None, :]]
        )
        for jac in [*hard, *jacobians[:-1]]:
            projector = projector - _row_space(jac @ projector, self.options.rank_tolerance)
        u, sigma, _ = np.linalg.svd(jacobians[-1] @ projector)
        rank = int(np.sum(sigma > self.options.rank_tolerance))
        m = h.sizes[k]
        rows = np.zeros((m, m))
        rows[:rank] = u[:, :rank].T
        lo = np.where(np.arange(m) < rank, 0.0, -np.inf)
        remaining = projector - _row_space(jacobians[-1] @ projector, self.options.rank_tolerance)
        return rows, lo, -lo, bool(np.linalg.norm(remaining) > 1e-6)


def _row_space(matrix: np.ndarray, tolerance: float) -> np.ndarray:
    """Orthogonal projector on the row space of ``matrix`` (SVD, rank-thresholded)."""
    _, sigma, vt = np.linalg.svd(matrix, full_matrices=False)
    basis = vt[sigma > tolerance]
    return basis.T @ basis
