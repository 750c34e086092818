"""Strict priorities as a sequence of NLPs, one per level (docs/model.md).

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
constraint qualification fails at a zero residual). Only the rows a level can still
change are kept: S_j holds the left singular vectors of J_j Z at level j's solution, Z
an orthonormal basis of the joint directions that keep the higher levels' kept rows,
padded with zero rows whose bounds are infinite, so every NLP has a fixed shape and is
built once. Joint limits and the inequality do not shrink Z: a lower level may leave
them, and a row it changes that way must be kept (counting them fixed let level 2 of the
-45° hold take its arm off the inequality and level 1 from 0.035 to 0.114 m). A lower
level's answer that raises a higher level's residual norm anyway (at a singular posture
a row can change at second order only: a straight arm bending) is refused; the level
keeps its start.

Each NLP has two solvers. When one Gauss-Newton step predicts the level's solution
within ``SQP_RADIUS`` of its start, CasADi's SQP method solves it first: qrqp QPs, full
steps, the Hessian 2 J_kᵀJ_k + εI of ‖e_k‖² (2I of ‖q - q_prev‖²) plus the exact
curvature of the kept rows. Near the solution it converges quadratically, in 2 to 7
iterations, to below 1e-9 m on an achievable level. IPOPT stops earlier there: its
tolerance bounds the gradient 2 J_kᵀe_k, which leaves ‖e_k‖ ≈ tol/(2σ_min), up to 2e-6 m
measured. When SQP is not tried or fails, IPOPT solves the level from the same start and,
if the level is achieved, SQP polishes IPOPT's answer. Every answer is re-checked against
the bounds, the inequality and the kept residuals with this module's tolerances; neither
solver's word alone is trusted. A level whose answer fails that re-check, or raises a higher
level's residual while its solver failed, keeps its start and its status says so ("kept its
start"): a failed solve never returns a posture that breaks a higher level. Nothing is
kept from one solve to the next but the compiled NLPs: SQP started from the previous
solve's multipliers saved 0.8 of 11 iterations per posture at 42 DOF and no measurable
time.
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from casadi_posture.compiled import Compiled
from casadi_posture.ik.hierarchy import Inequality, TaskHierarchy
from casadi_posture.ik.result import ACHIEVED_TOLERANCE, IKResult, active_constraints

#: Re-check tolerances on the returned posture: bounds [rad], aᵀq - b [rad], kept rows
#: and residual norms of the higher levels [task units].
BOUND_TOLERANCE = 1e-9
KEPT_RESIDUAL_TOLERANCE = 1e-8

#: ε of the Gauss-Newton Hessian [task units² per rad²]: keeps the QPs strictly convex
#: along the directions a level leaves free and damps the steps along nearly singular
#: ones (with 1e-9, steps of 2 rad from 30° off led SQP to other minima than IPOPT's).
REGULARISATION = 1e-6

#: SQP stops when the constraints hold to ``SQP_PRIMAL_TOLERANCE`` [task units] and the
#: gradient of the Lagrangian is below ``SQP_DUAL_TOLERANCE`` [objective units per rad].
SQP_PRIMAL_TOLERANCE = 1e-10
SQP_DUAL_TOLERANCE = 1e-9
#: SQP iterations, and QP iterations per SQP iteration, before IPOPT takes over (2 to 10
#: SQP iterations measured from starts within ``SQP_RADIUS``). SQP is used only when
#: ``max_iterations`` is at least ``SQP_MAX_ITERATIONS``: a lower limit is IPOPT's.
SQP_MAX_ITERATIONS = 20
QP_MAX_ITERATIONS = 50

#: SQP is tried on a level when one damped Gauss-Newton step from its start, the joints
#: within ``PREDICTION_MARGIN`` [rad] of a limit held, moves no joint farther than this
#: [rad], and its answer is refused if it moved farther: from farther, its full steps
#: reach other points of a level's solution set than IPOPT's path, and lower levels
#: other minima (of 40 starts 8° off on a 42-DOF humanoid, 0.25 rad let 2 end worse than
#: IPOPT, 0.2 rad 1, as many as IPOPT itself from starts moved by 1e-6 rad).
SQP_RADIUS = 0.2
PREDICTION_MARGIN = 0.05

#: SQP starts this far [rad] inside the joint ranges, as IPOPT does: from a joint at its
#: limit in a straight limb the gradient of ‖e_k‖² vanishes, and SQP stopped there
#: (0.27 m off the ankle targets of a 28-DOF humanoid standing upright).
BOUND_PUSH = 1e-3


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


@dataclass(frozen=True)
class _Derivatives:
    """A level's objective gradient (one reverse sweep), the Jacobian of its constraints
    (the inequality's row, then each higher level's kept rows S_j J_j, from the
    hierarchy's Jacobians) and its objective's Gauss-Newton Hessian."""

    gradient: ca.SX
    jacobian: ca.SX
    hessian: ca.SX


@dataclass
class _Level:
    """One level's NLP (CasADi's dict), its SQP solver (None: the options leave too few
    iterations for it) and its IPOPT, built at first use."""

    nlp: dict
    sqp: Compiled | None
    ipopt: Compiled | None = None


class LexicographicSolver:
    """One parametric NLP per priority level, built once per problem structure, each on its
    first use (a comfort level determines every DOF, so the final ‖q - q_prev‖² level of
    such a hierarchy is never built): an IPOPT solver and an SQP one (none when
    ``max_iterations`` is below ``SQP_MAX_ITERATIONS``). After a solve, ``methods`` says per
    level whose answer was kept: "sqp", "ipopt", "ipopt+sqp" (polished) or "start" (an
    answer that raised a higher level's residual, refused)."""

    name = "lexicographic"

    def __init__(
        self, hierarchy: TaskHierarchy, options: LexicographicOptions | None = None
    ) -> None:
        self.hierarchy = hierarchy
        self.options = options or LexicographicOptions()
        body = hierarchy.body
        self._built: list[_Level | None] = [None] * (hierarchy.depth + 1)
        f = hierarchy.function
        dense = [ca.densify(v) for v in hierarchy.residuals + hierarchy.jacobians]
        self._values = Compiled(
            ca.Function("levels", [body.q, hierarchy.p], dense, f.name_in(), f.name_out())
        )
        self._bind(hierarchy)

    def rebind(self, hierarchy: TaskHierarchy) -> LexicographicSolver:
        """This solver on ``hierarchy``, of the same structure (other target values or joint
        ranges): the compiled NLPs and their buffers are shared (use both in one thread);
        nothing of earlier solves is kept."""
        other = copy.copy(self)
        other._bind(hierarchy)
        return other

    def _bind(self, hierarchy: TaskHierarchy) -> None:
        """Solve on ``hierarchy``'s targets and joint ranges from now on."""
        self.hierarchy, self.methods = hierarchy, []
        self._lower, self._upper = hierarchy.body.lower, hierarchy.body.upper
        push = np.minimum(BOUND_PUSH, (self._upper - self._lower) / 4)
        self._inside = (self._lower + push, self._upper - push)

    def _level(self, k: int) -> _Level:
        """The NLP of level k+1 and its SQP solver, built on first use (shared by the solvers
        ``rebind`` makes)."""
        built = self._built[k]
        if built is None:
            nlp, derivatives = self._problem(k)
            sqp = None
            if self.options.max_iterations >= SQP_MAX_ITERATIONS:
                sqp = Compiled(self._sqp(k, nlp, derivatives))
            built = self._built[k] = _Level(nlp, sqp)
        return built

    def _ipopt_of(self, k: int) -> Compiled:
        """Level k+1's IPOPT, built at its first use: a level SQP settles from a nearby start
        never needs it (half of a cold start's 0.3 s of solver builds at 29 DOF)."""
        level = self._level(k)
        if level.ipopt is None:
            level.ipopt = Compiled(self._ipopt(k, level.nlp))
        return level.ipopt

    def _problem(self, k: int) -> tuple[dict, _Derivatives]:
        """The NLP of level k+1 (k = depth: the final ‖q - q_prev‖² level) and its
        derivatives: the kept rows' Jacobian from the hierarchy's (not differentiated
        again), the objective's gradient by one reverse sweep (cheaper to evaluate than
        2 J_kᵀe_k: 14 100 instructions against 37 700 with the comfort level at 29 DOF)."""
        h, body = self.hierarchy, self.hierarchy.body
        n, q = body.n, body.q
        q_prev, a, b = ca.SX.sym("q_prev", n), ca.SX.sym("a", n), ca.SX.sym("b")
        params, g, jacobian = [h.p, q_prev, a, b], [ca.dot(a, q)], [a.T]
        for j in range(k):
            m = h.sizes[j]
            rows, kept = ca.SX.sym(f"S{j + 1}", m, m), ca.SX.sym(f"e{j + 1}_star", m)
            params += [ca.vec(rows), kept]
            g.append(rows @ (h.residuals[j] - kept))
            jacobian.append(rows @ h.jacobians[j])
        if k < h.depth:
            e, J = h.residuals[k], h.jacobians[k]
            f = ca.sumsqr(e)
            gradient = ca.gradient(f, q)
            hessian = 2 * J.T @ J + REGULARISATION * ca.SX.eye(n)
        else:
            f, gradient, hessian = ca.sumsqr(q - q_prev), 2 * (q - q_prev), 2 * ca.SX.eye(n)
        nlp = {"x": q, "p": ca.vertcat(*params), "f": f, "g": ca.vertcat(*g)}
        return nlp, _Derivatives(gradient, ca.vertcat(*jacobian), hessian)

    def _ipopt(self, k: int, nlp: dict) -> ca.Function:
        """IPOPT on level k+1, exact Hessian."""
        opts = self.options
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
            {
                "expand": True,
                "print_time": False,
                "error_on_fail": False,
                "calc_lam_p": False,
                "ipopt": ipopt,
            },
        )

    def _sqp(self, k: int, nlp: dict, derivatives: _Derivatives) -> ca.Function:
        """CasADi's SQP method on level k+1: the objective's Gauss-Newton Hessian plus the
        exact curvature of the kept rows (λ of rows S_j(e_j - e_j*) weighs ∇²e_j by
        S_jᵀλ), full steps (no line search: it is used near the solution only, and there
        its Armijo test failed on steps of 1e-16 rad, which stalled the multipliers). The
        gradient (dense: sqpmethod misreads a sparse one) and the constraints' Jacobian are
        given (``jac_fg``), so sqpmethod differentiates nothing itself."""
        x, p = nlp["x"], nlp["p"]
        sigma, lam_g = ca.SX.sym("lam_f"), ca.SX.sym("lam_g", nlp["g"].numel())
        curvature, _ = ca.hessian(ca.dot(lam_g, nlp["g"]), x)
        hessian = sigma * derivatives.hessian + curvature
        hess_lag = ca.Function(
            f"level{k + 1}_hess_lag",
            [x, p, sigma, lam_g],
            [hessian],
            ["x", "p", "lam_f", "lam_g"],
            ["hess_gamma_x_x"],
        )
        jac_fg = ca.Function(
            f"level{k + 1}_jac_fg",
            [x, p],
            [nlp["f"], ca.densify(derivatives.gradient), nlp["g"], derivatives.jacobian],
            ["x", "p"],
            ["f", "grad_f_x", "g", "jac_g_x"],
        )
        qrqp = {
            "print_iter": False,
            "print_header": False,
            "print_info": False,
            "error_on_fail": False,
            "max_iter": QP_MAX_ITERATIONS,
        }
        return ca.nlpsol(
            f"level{k + 1}_sqp",
            "sqpmethod",
            nlp,
            {
                "expand": True,
                "print_time": False,
                "error_on_fail": False,
                "calc_lam_p": False,
                "hess_lag": hess_lag,
                "jac_fg": jac_fg,
                "qpsol": "qrqp",
                "qpsol_options": qrqp,
                "print_header": False,
                "print_iteration": False,
                "print_status": False,
                "tol_pr": SQP_PRIMAL_TOLERANCE,
                "tol_du": SQP_DUAL_TOLERANCE,
                "max_iter": SQP_MAX_ITERATIONS,
                "max_iter_ls": 0,
                # a first try whose failures IPOPT takes over: a full step that leaves the
                # region where the comfort level's effort is finite is one of them
                "show_eval_warnings": False,
            },
        )

    def solve(self, q0: np.ndarray, inequality: Inequality | None = None) -> IKResult:
        """Solve the levels in order from ``q0`` [rad], each started from the last."""
        start = time.perf_counter()
        h = self.hierarchy
        a = np.zeros(h.body.n) if inequality is None else np.asarray(inequality.a, dtype=float)
        b = np.inf if inequality is None else float(inequality.b)
        q_prev = np.clip(np.asarray(q0, dtype=float), self._lower, self._upper)
        fixed = np.concatenate([h.targets, q_prev, a, [min(b, 1e20)]])
        q = q_prev
        residuals, jacobians = self._evaluate(q)
        kept: list[tuple[np.ndarray, np.ndarray]] = []
        self.methods = []
        iterations, status, failure, redundant = 0, "Solve_Succeeded", "", True
        for k in range(h.depth + 1):
            if k == h.depth and not redundant:
                break
            args = {
                "p": np.concatenate([fixed, *[np.concatenate([r.ravel("F"), e]) for r, e in kept]]),
                "lbx": self._lower,
                "ubx": self._upper,
                "lbg": np.concatenate([[-np.inf], *[_row_bounds(r) for r, _ in kept]]),
                "ubg": np.concatenate([[b], *[-_row_bounds(r) for r, _ in kept]]),
            }
            if k < h.depth:
                error, jacobian = residuals[k], jacobians[k]
            else:
                error, jacobian = q - q_prev, np.eye(q.size)
            near = self._near(q, error, jacobian, jacobians, kept, inequality)
            q_level, failure, spent = self._solve_level(
                k, q, float(error @ error), args, inequality, near
            )
            iterations += spent
            adopted = False
            if q_level is not q:
                values = self._evaluate(q_level)
                growth = max(
                    (np.linalg.norm(values[0][j]) - np.linalg.norm(residuals[j]) for j in range(k)),
                    default=0.0,
                )
                adopted = growth <= KEPT_RESIDUAL_TOLERANCE
                if adopted:
                    q, (residuals, jacobians) = q_level, values
                elif failure or not self._feasible(q, inequality):
                    grew = f"a higher level's residual grew by {growth:.3g}"
                    failure += "; " * bool(failure) + grew
                else:
                    self.methods[-1] = "start"
            if failure:
                status = f"level {k + 1}: {failure}" + "; kept its start" * (not adopted)
                break
            if k < h.depth:
                rows, redundant = self._kept_rows(jacobians, kept, k)
                kept.append((rows, residuals[k]))
        at_limits, active = active_constraints(h.body, q, inequality)
        return IKResult(
            self.name,
            q,
            np.array([np.linalg.norm(e) for e in residuals]),
            iterations,
            status,
            not failure,
            at_limits,
            active,
            time.perf_counter() - start,
            len(self.methods),
        )

    def _evaluate(self, q: np.ndarray) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """Every level's residual and Jacobian at ``q``, in one compiled call."""
        h, n = self.hierarchy, self.hierarchy.body.n
        out = list(self._values(q=q, targets=h.targets).values())
        residuals = [e.copy() for e in out[: h.depth]]
        jacobians = [j.reshape(n, -1).T.copy() for j in out[h.depth :]]
        return residuals, jacobians

    def _near(
        self,
        q: np.ndarray,
        error: np.ndarray,
        jacobian: np.ndarray,
        jacobians: list[np.ndarray],
        kept: list[tuple[np.ndarray, np.ndarray]],
        inequality: Inequality | None,
    ) -> bool:
        """Whether one damped Gauss-Newton step on ‖``error``‖² (``jacobian`` its Jacobian)
        from ``q`` moves no joint farther than ``SQP_RADIUS``, along the directions that
        keep the higher levels' rows and the inequality if active and leave the joints
        within ``PREDICTION_MARGIN`` of a limit where they are."""
        free = (q > self._lower + PREDICTION_MARGIN) & (q < self._upper - PREDICTION_MARGIN)
        active = active_constraints(self.hierarchy.body, q, inequality)[1]
        basis = self._free_basis(jacobians, kept, free, [inequality.a[None, :]] if active else [])
        u, sigma, vt = self._projected_svd(jacobian, basis)
        step = basis @ (vt.T @ (sigma / (sigma**2 + REGULARISATION / 2) * (u.T @ error)))
        reach = np.clip(q - step, self._lower, self._upper) - q
        return bool(np.max(np.abs(reach), initial=0.0) <= SQP_RADIUS)

    def _solve_level(
        self,
        k: int,
        start: np.ndarray,
        objective: float,
        args: dict,
        inequality: Inequality | None,
        near: bool,
    ) -> tuple[np.ndarray, str, int]:
        """Level k+1 from ``start``, where its objective is ``objective``: SQP if the
        solution is ``near``; if not, or if SQP fails, IPOPT, whose answer SQP polishes if
        the level is achieved (an unachieved level stays as IPOPT ends it: polishing the
        posture level of a 42-DOF humanoid failed in 20 iterations); without SQP solvers,
        IPOPT alone. Returns the posture (``start`` itself when no answer beats it), what
        went wrong ('' if nothing) and the iterations spent."""
        sqp, spent = self._level(k).sqp, 0
        if near and sqp is not None:
            inside = np.clip(start, *self._inside)
            q, failure, _, spent = self._attempt(
                sqp, start, inside, objective, args, inequality, SQP_RADIUS
            )
            if not failure:
                self.methods.append("sqp")
                return q, "", spent
        q, failure, out, more = self._attempt(
            self._ipopt_of(k), start, start, objective, args, inequality, np.inf
        )
        self.methods.append("ipopt")
        achieved = k < self.hierarchy.depth and out["f"][0] <= ACHIEVED_TOLERANCE**2
        if failure or q is start or sqp is None or not achieved:
            return q, failure, spent + more
        polished, unpolished, _, most = self._attempt(
            sqp,
            q,
            q,
            float(out["f"][0]),
            {**args, "lam_g0": out["lam_g"]},
            inequality,
            SQP_RADIUS,
        )
        if not unpolished and polished is not q:
            q, self.methods[-1] = polished, "ipopt+sqp"
        return q, "", spent + more + most

    def _attempt(
        self,
        solver: Compiled,
        start: np.ndarray,
        x0: np.ndarray,
        objective: float,
        args: dict,
        inequality: Inequality | None,
        radius: float,
    ) -> tuple[np.ndarray, str, dict, int]:
        """``solver`` from ``x0`` on a level whose start ``start`` has the objective
        ``objective``. Returns the posture (``start`` when the answer is no better or fails
        the re-check, or moved a joint farther than ``radius`` [rad] from ``start``), what is
        wrong with the answer ('' if nothing), the solver's output and its iterations."""
        out = solver(**args, x0=x0)
        stats = solver.stats()
        q, problem = start, ""
        if not (self._feasible(start, inequality) and objective < out["f"][0]):
            answer = out["x"].copy()
            problem = self._check(answer, out["g"], args["lbg"], args["ubg"])
            moved = float(np.max(np.abs(answer - start)))
            if not problem and moved > radius:
                problem = f"moved {moved:.3g} rad"
            if not problem:
                q = answer
        failure = "" if stats["success"] else stats["return_status"]
        failure += "; " * bool(failure and problem) + problem
        return q, failure, out, int(stats.get("iter_count", 0))

    def _feasible(self, start: np.ndarray, inequality: Inequality | None) -> bool:
        """Whether a level's start meets all of the level's constraints. It meets the kept
        rows by construction (they are zero there) and the bounds; only the inequality is
        checked. A feasible start with a smaller objective is kept instead of the solver's
        answer: on a level whose minimisers form a set IPOPT can wander along it and stop
        "acceptable" farther from zero than where it began (1e-6 m from a 9e-8 m start,
        measured on the line + plane problem)."""
        return inequality is None or inequality.a @ start <= inequality.b + BOUND_TOLERANCE

    def _check(self, q: np.ndarray, g: np.ndarray, lbg: np.ndarray, ubg: np.ndarray) -> str:
        """What the returned posture violates, beyond this module's tolerances ('' if nothing)."""
        if np.any(q < self._lower - BOUND_TOLERANCE) or np.any(q > self._upper + BOUND_TOLERANCE):
            return "joint limit exceeded"
        if g[0] > ubg[0] + BOUND_TOLERANCE:
            return f"inequality violated by {g[0] - ubg[0]:.3g}"
        excess = np.maximum(g[1:] - ubg[1:], lbg[1:] - g[1:])
        if excess.size and np.max(excess) > KEPT_RESIDUAL_TOLERANCE:
            return f"higher-level residual changed by {np.max(excess):.3g}"
        return ""

    def _kept_rows(
        self, jacobians: list[np.ndarray], kept: list[tuple[np.ndarray, np.ndarray]], k: int
    ) -> tuple[np.ndarray, bool]:
        """S_k: the rows of e_k that the lower levels can still change (``jacobians`` at
        level k+1's answer; ``kept``: the higher levels' rows), zero-padded to m_k × m_k;
        and whether joint space is still redundant below level k+1."""
        free = np.ones(jacobians[k].shape[1], dtype=bool)
        basis = self._free_basis(jacobians, kept, free, [])
        u, sigma, _ = self._projected_svd(jacobians[k], basis)
        rows = np.zeros((u.shape[0], u.shape[0]))
        rows[: sigma.size] = u.T
        return rows, sigma.size < basis.shape[1]

    def _free_basis(
        self,
        jacobians: list[np.ndarray],
        kept: list[tuple[np.ndarray, np.ndarray]],
        free: np.ndarray,
        held: list[np.ndarray],
    ) -> np.ndarray:
        """Orthonormal columns (n × r) spanning the motions of the joints ``free`` that keep
        the higher levels' rows (``kept``, with ``jacobians``) and the rows ``held``."""
        rows = [r @ jac for (r, _), jac in zip(kept, jacobians, strict=False)] + held
        n = free.size
        _, sigma, vt = np.linalg.svd(np.vstack([np.zeros((0, n)), *rows])[:, free])
        rank = np.count_nonzero(sigma > self.options.rank_tolerance)
        basis = np.zeros((n, vt.shape[0] - rank))
        basis[free] = vt[rank:].T
        return basis

    def _projected_svd(
        self, jacobian: np.ndarray, basis: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """U, Σ, Vᵀ of ``jacobian @ basis`` truncated to its rank: U's columns span the rows
        of the level's residual that the motions ``basis`` change."""
        u, sigma, vt = np.linalg.svd(jacobian @ basis, full_matrices=False)
        rank = np.count_nonzero(sigma > self.options.rank_tolerance)
        return u[:, :rank], sigma[:rank], vt[:rank]


def _row_bounds(rows: np.ndarray) -> np.ndarray:
    """Lower bounds of the kept rows S (e - e*): 0 on a kept row, -inf on a padding row."""
    return np.where(np.any(rows != 0.0, axis=1), 0.0, -np.inf)
