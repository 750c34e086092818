"""The paper's IK solver: strict priorities by nullspace projection (Baerlocher & Boulic 2004;
docs/model.md).

One iteration from the posture q [rad] evaluates every level's residual e_k and Jacobian
J_k in one compiled CasADi call (into buffers, ``Function.buffer``), then sweeps the levels
numerically:

    J̃_k = J_k P_{k-1}
    Δq_k = Δq_{k-1} + J̃_k^{+λ_k} (Δx_k - J_k Δq_{k-1})      damped, in the step only
    P_k  = P_{k-1} - J̃_k⁺ J̃_k                                undamped, rank-thresholded

with Δx_k = -e_k clamped per task (``Task.step_limit``), and q ← clip(q + Δq, limits).
P_k = Z_k Z_kᵀ is carried as an orthonormal basis Z_k (n×r_k) of the motions the levels
above leave free, so J̃_k = J_k Z_{k-1} is only m_k×r_{k-1}. With its SVD U S Vᵀ:

    Δq_k = Δq_{k-1} + Z_{k-1} V diag(s / (s² + λ_k²)) Uᵀ (Δx_k - J_k Δq_{k-1})
    Z_k  = Z_{k-1} V_⊥

over the singular values s above ``rank_tolerance`` (those below are numerical zeros:
kept in the damped step, a 1e-16 one adds s/λ² ≈ 1e-10 rad of noise per iteration), V_⊥
the right singular vectors of the others. One free direction z left: J̃_k is a column c,
Δq_k = Δq_{k-1} + z cᵀr/(cᵀc + λ_k²). A level of joint references on every DOF has
J_k = I (up to row order): J̃_k = P_{k-1} is symmetric idempotent, the damped step is
P_{k-1}(Δx_k - Δq_{k-1})/(1 + λ_k²) and nothing is left free below it; joint references
on some DOFs select rows of Z. Neither needs its Jacobian evaluated.

Joint limits and the inequality aᵀq ≤ b: joints held at a limit are moved onto it and
removed from Z_0; the inequality, while held, is the highest-priority equality
aᵀΔq = b - aᵀq, undamped. See ``NullspaceSolver._held_step`` for when they are held;
in ``NullspaceSolver.solve``, of what a step takes beyond, the clamping loop holds first
what it reaches first (``FIRST_REACHED``).
Near a solution the iterations are extrapolated (``_Anderson``).

The damping floor (``NullspaceSolver.solve`` only; ``NullspaceSolver.iteration``
is the plain step above). Each level below the first is linearised without the curvature
of the task constraints above it, a term of the order of its residual r_k times the
curvature of those tasks. Along a direction in which J̃_k is nearly singular (an
algorithmic singularity: the posture of the legs reachable, within the feet and balance
task, only through the arms' small share of the centre of mass; a gaze reachable only by
bending the trunk; an arm straightening at its elbow limit) the step s·(uᵀr)/(s² + λ²)
trusts a model that curvature dominates: with λ = 1e-3 it amplifies the error up to
1/(2λ) = 500 times, radians of joint motion that break the levels above at second order,
slam joints into their limits and leave the iteration wandering. So the solve uses

    Δq_k = Δq_{k-1} + Z_{k-1} V diag(s / (max(s², μ_k) + λ_k²)) Uᵀ r_k,   μ_k = κ_k ‖r_k‖

with r_k = Δx_k - J_k Δq_{k-1}: the Levenberg-Marquardt damping proportional to the
residual, applied only to the singular values it exceeds, so a well-conditioned direction
takes the paper's step (and a level that is achieved, r_k → 0, the undamped Gauss-Newton
step). κ_k starts at ``NullspaceOptions.curvature`` on every level below the first (level
1 has no task above it; a level of joint references on every DOF, J̃_k = P_{k-1}, is
never nearly singular) and rises while the steps oscillate (``REVERSAL``). With the same
joints held, a step is zero exactly where the paper's is (the gains differ, not the
directions they act on): the floor changes the path, not where it may stop; which joints
stay held is decided by the free step of the solve's own sweep
(``NullspaceSolver._held_step``). A missed level whose residual lies along the
directions the floor lifts is at rest out of reach, at a singularity of J̃_k: the sweep
stops there and the levels below wait (``OUT_OF_REACH``).
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import casadi as ca
import numpy as np

from casadi_posture.ik.hierarchy import Inequality, TaskHierarchy
from casadi_posture.ik.result import (
    ACHIEVED_TOLERANCE,
    ACTIVE_TOLERANCE,
    IKResult,
    active_constraints,
)
from casadi_posture.ik.tasks import JointReference

_TINY = 1e-300


@dataclass(frozen=True)
class NullspaceOptions:
    """Settings of the nullspace-projection solver.

    ``damping`` λ per task level [task units] (one value for all levels, or one per
    level); ``rank_tolerance`` [task units per rad]; a joint or the inequality is caught
    by its limit when the step would take it more than ``limit_slack`` [rad] beyond;
    ``acceleration_memory`` steps are used to extrapolate (0: plain iterations);
    ``curvature`` κ [(task unit per rad)² per task unit] is the damping floor's first
    factor (module docstring; 0: the paper's damped steps alone).

    Stop: when the largest joint step is below ``tolerance`` [rad], or after
    ``max_iterations``. The step is the iteration's own correction, zero exactly at its
    fixed point, whether or not the lower levels can be achieved; a residual test could not
    stop on a level in conflict with a higher one, whose residual stays large.

    Stall: an inequality that conflicts with a higher level makes the recursion limit-cycle.
    The iteration stops with status ``stalled`` when ``stall_iterations`` iterations in a row
    bring no progress, or when it comes to rest at a posture worse than one it passed
    (``REST_MARGIN``). Progress is a lexicographic decrease of (inequality violation,
    level-1 residual, level-2 residual, ...) beyond ``PROGRESS_MARGIN``, or a step shorter
    than any since the best merit (``STEP_PROGRESS``). A run that does not converge
    returns the best posture it passed.

    Saddle: a run at rest that misses a level whose own gradient vanishes there (no higher
    level holds it off) is tested for negative curvature of that level and restarted from
    a posture that lowers it (``STATIONARY``); if no restart does better, the status is
    ``stalled: level k at a saddle, residual r``, not ``converged``. A rest at which that
    level pulls a held joint limit or the held inequality back inside (``KKT_TOLERANCE``) is
    restarted with that constraint released; if no restart does better, the status is
    ``stalled: level k held at a limit it pulls away from, ...``.
    """

    damping: float | tuple[float, ...] = 1e-3
    rank_tolerance: float = 1e-9
    tolerance: float = 1e-8
    max_iterations: int = 1000
    limit_slack: float = 1e-12
    stall_iterations: int = 30
    acceleration_memory: int = 5
    curvature: float = 0.2


#: Margins (relative, absolute [task units]) of a lexicographic improvement: of progress,
#: above the numerical noise around an achieved level (about 1e-13); and of a rest posture
#: worse than one passed, above what a level at its convergence floor (a step of
#: ``tolerance``) trades with the next (6.5e-10 measured at 7 DOF) and far below what
#: matters (``ACHIEVED_TOLERANCE``, 1e-4).
PROGRESS_MARGIN = (1e-9, 1e-10)
REST_MARGIN = (1e-6, 1e-8)

#: A better posture passed within this distance [rad, largest joint difference] of the rest
#: posture is the same answer: near a level in conflict with a higher one (or with the
#: inequality) the higher level's residual changes with the square of the distance, the lower
#: one's in proportion to it, and a tail of converging iterates trades them. Measured on the
#: 2-DOF benchmark arm under its fatigue constraint: an iterate about 9e-6 rad before the
#: rest posture had level 2 lower by 6.9e-6 (above ``REST_MARGIN``), level 1 equal to 8
#: digits, and the run was called stalled (138 of the 1201 steps of its simulation fell back
#: on the other solver). The rest at both limits ``REST_MARGIN`` is for (tests/test_ik.py's
#: limited arm) lies 0.17 rad from the better posture.
REST_DISTANCE = ACHIEVED_TOLERANCE

#: A step shorter than this fraction of the shortest one since the best merit is progress
#: too: near a minimum the residuals change with the square of the step, below any margin,
#: while the step itself still shrinks geometrically; in a limit cycle it does not. (Since
#: the best merit, not since the start: a short step early in a long path must not make
#: the geometric tail look like a stall.)
STEP_PROGRESS = 0.999


#: Saddles (``NullspaceSolver._leave_saddles``). A level whose own gradient Jₖᵀeₖ is
#: below ``STATIONARY`` times ‖Jₖ‖‖eₖ‖ (outside what the joint limits and the inequality
#: block) is not held off by a higher level: at rest with it missed, the iteration sits where
#: its linear model sees no way down. Its second derivative is then tested along the motions
#: that none of the levels down to it sees at first order (singular values of their stacked
#: Jacobians below ``SADDLE_RANK`` times the largest), by central differences of ``SADDLE_PROBE``
#: [rad]. A direction of negative curvature makes the rest posture a saddle: the iteration
#: restarts from a posture along it (``SADDLE_STEPS`` [rad], the first that lowers the level's
#: residual), at most ``SADDLE_RESTARTS`` times. Measured on the 7-DOF benchmark arm, wrist ▸
#: every joint upright, from the upright posture: the iteration came to rest with the arm
#: straight at its elbow limit, the wrist 6.0 cm beyond the target along the arm, and called
#: it converged; ‖e_1‖² has a curvature of -0.0094 m² per rad² along the shoulder and elbow
#: flexion that keep the wrist still at first order (bending the elbow brings the wrist
#: closer). One restart, 0.9° of elbow flexion away, reaches the target and the numpy
#: reference's posture.
STATIONARY = 1e-6
SADDLE_RANK = 1e-6
SADDLE_PROBE = 1e-3
SADDLE_STEPS = (0.02, 0.05, 0.1, 0.2, 0.5)
SADDLE_RESTARTS = 3

#: First-order optimality (``NullspaceSolver._unbalanced``). The clamping loop holds a
#: joint at its limit when the sweep's Gauss-Newton step takes it beyond, which is not the
#: sign of its multiplier: at rest the first missed level k may still pull a held joint (or
#: the held inequality) back inside, so that it could go lower with the levels above kept.
#: At rest with such a level, its gradient Jₖᵀeₖ is tested for the Karush-Kuhn-Tucker
#: conditions with the levels above as equalities and the held limits and inequality as
#: inequalities (nonnegative multipliers, ``_nnls``). A remainder above ``KKT_TOLERANCE``
#: times ‖Jₖ‖‖eₖ‖ is the active-set method's cue: the constraint with the most negative
#: least-squares multiplier is released, and the run restarts from the rest posture with the
#: others held for its first iteration (``SADDLE_RESTARTS`` in all with the saddles; the
#: better rest is kept). If no restart does better, the status is ``stalled``. Measured on the
#: 28-DOF benchmark body under the paper's constraint on the right hip flexion (a step of the
#: 20-minute simulation; 28 of its 1201 steps fell back on the other solver): the right hip
#: abduction held at its upper limit with a multiplier of -0.0044 for the feet level, the
#: ankles 0.348 m off their targets where 0.286 m is reachable (the lexicographic solver's
#: answer); the numpy reference of benchmarks/scaling.py rests there too. Released, it moves
#: inside its range and the run converges to the lexicographic solver's answer (0.2861823 m,
#: 116 iterations in all).
KKT_TOLERANCE = 1e-4


#: The damping floor of ``NullspaceSolver.solve`` (module docstring): when a step of at
#: least ``ACCELERATED_STEP`` turns back on the one before by more than
#: arccos(-``REVERSAL``) (a period-2 oscillation: the step overshoots along a direction the
#: Gauss-Newton model misjudges), every κ_k is multiplied by ``FLOOR_RAISE``, up to
#: ``FLOOR_CAP`` times κ; when it keeps its direction, divided by ``FLOOR_LOWER``, down to
#: κ. Measured on the standing body: the leg posture under the feet and balance task, the
#: knees near straight, overshoots by a factor of 2.07 (an eigenvalue of -1.07 of the
#: iteration, a limit cycle of 0.13 to 0.25 rad in the knees and hips).
REVERSAL = 0.5
FLOOR_RAISE = 4.0
FLOOR_LOWER = 2.0
FLOOR_CAP = 1e4

#: A level below the first comes to rest out of reach where J̃_k loses rank: its gradient J̃_kᵀe_k
#: vanishes with e_k ≠ 0, so e_k lies along a left singular vector whose singular value s goes to
#: zero at the rest (in proportion to the distance d from it). The motions the levels below may use,
#: Z_k, leave out that singular vector's right one, v, which turns inside the nullspace at a rate of
#: about 1/s = 1/d per radian of q: a level below pushing against level k (the comfort level) is
#: projected on a subspace that swings with every iterate, and the iteration cannot settle. When the
#: part of r_k that the well-conditioned directions see (s² ≥ μ_k, not lifted by the floor) is at
#: most ``OUT_OF_REACH`` of ‖r_k‖² and ‖r_k‖ is above ``ACHIEVED_TOLERANCE``, level k is at rest out
#: of reach and the sweep stops there: the levels below wait while it re-converges (they moved it
#: there, on the way). Its fixed points are the paper's fixed points of levels 1..k (first-order
#: minima of level k with the levels above kept; the saddle and KKT checks still apply). Measured on
#: the standing body, a 1.65 m woman's hands at a shelf 1.6 m high and 0.62 m ahead (out of reach;
#: tests/test_nullspace_status.py; measured with the earlier de Leva leg lengths): at the
#: lexicographic solver's answer, the hands 0.0977 m off with the arms straight, J̃_2's smallest
#: singular value is 5.5e-5 and carries the whole residual, and the comfort level's step turns the
#: iteration with an eigenvalue of -176 (wrist flexion); the run oscillated with steps of 0.02 to
#: 0.4 rad, level 1 broken by 1e-5 to 4e-3 m, and ended ``stalled`` at its start (62 iterations;
#: allowed 3000, with a floor kept from falling back below where it reversed, it still wandered with
#: steps of 2e-5 rad). Now: converged in 26 iterations, the hands 0.0976738 m off (the lexicographic
#: solver: 0.0976739), no joint more than 0.36° from its posture. The test also holds on the way (5
#: of the 67 sweeps from the 42-DOF benchmark body's upright start: 88 iterations instead of 70,
#: ending in the lexicographic solver's comfort minimum, 1.306 instead of 1.409).
OUT_OF_REACH = 1e-2


def _out_of_reach(along: np.ndarray, lifted: np.ndarray, residual: np.ndarray) -> bool:
    """Whether a level is at rest out of reach (``OUT_OF_REACH``): its ``residual`` r_k
    [task units] is missed and lies along the directions the damping floor lifts
    (``lifted``; ``along`` = Uᵀr_k, its components on the left singular vectors)."""
    square = float(residual @ residual)
    seen = along[~lifted]
    return square > ACHIEVED_TOLERANCE**2 and float(seen @ seen) <= OUT_OF_REACH * square


def _better(merit: np.ndarray, best: np.ndarray, margin: tuple[float, float]) -> bool:
    """Whether ``merit`` (violation, level residuals) is lexicographically below ``best``
    by more than ``margin`` (relative, absolute) at the first level where they differ."""
    relative, absolute = margin
    for value, reference in zip(merit, best, strict=True):
        tolerance = relative * reference + absolute
        if value < reference - tolerance:
            return True
        if value > reference + tolerance:
            return False
    return False


def _nnls(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """x ≥ 0 minimising ‖a x - b‖ (Lawson & Hanson 1974, active set; a few columns)."""
    x, free = np.zeros(a.shape[1]), np.zeros(a.shape[1], dtype=bool)
    tolerance = 1e-12 * (1.0 + float(np.abs(a).max(initial=0.0) * np.abs(b).max(initial=0.0)))
    for _ in range(3 * a.shape[1]):
        w = a.T @ (b - a @ x)
        if free.all() or w[~free].max() <= tolerance:
            break
        free[np.flatnonzero(~free)[np.argmax(w[~free])]] = True
        while True:
            z = np.zeros_like(x)
            z[free] = np.linalg.lstsq(a[:, free], b, rcond=None)[0]
            if z[free].min(initial=np.inf) > 0.0:
                break
            bad = free & (z <= 0.0)
            alpha = np.min(x[bad] / (x[bad] - z[bad]))
            x += alpha * (z - x)
            free &= x > tolerance
        x = z
    return x


def _svd(a: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """U, s and the square Vᵀ of ``a`` (m×r); a single row (the held inequality) in closed
    form, its Vᵀ the Householder reflection that takes its direction v to ∓e_1. A tall
    ``a`` (m ≥ r: the comfort level's 87 rows at 29 DOF) gets the thin U, m×r, which is all
    the sweep reads, and its Vᵀ is square anyway: half the time of the full one."""
    m, r = a.shape
    if m > 1:
        return np.linalg.svd(a, full_matrices=m < r)
    s = float(np.sqrt(a[0] @ a[0]))
    if s == 0.0:
        return np.ones((1, 1)), np.zeros(1), np.eye(a.shape[1])
    h = a[0] / s
    sign = 1.0 if h[0] >= 0.0 else -1.0
    h[0] += sign
    return np.array([[-sign]]), np.array([s]), np.eye(a.shape[1]) - np.outer(h, h / (sign * h[0]))


@dataclass(frozen=True)
class _Held:
    """The hard constraints an iteration holds: ``side`` per joint (-1 at its lower limit,
    +1 at its upper, 0 free; None when no joint is held) and whether the inequality is an
    equality."""

    side: np.ndarray | None
    inequality: bool

    def __bool__(self) -> bool:
        return self.inequality or self.side is not None

    def same(self, other: _Held) -> bool:
        if self.side is None or other.side is None:
            return self.inequality == other.inequality and self.side is other.side
        return self.inequality == other.inequality and np.array_equal(self.side, other.side)

    def union(self, other: _Held | None) -> _Held:
        """What either holds (a joint held by both is held at the same limit)."""
        if other is None:
            return self
        if self.side is None or other.side is None:
            side = other.side if self.side is None else self.side
        else:
            side = np.where(self.side != 0, self.side, other.side)
        return _Held(side, self.inequality or other.inequality)


#: Nothing held.
_NOTHING = _Held(None, False)


class _Step(NamedTuple):
    """One iteration: the ``merit`` at its start (inequality violation, ‖e_k‖ per level),
    the posture ``q`` [rad] it reaches, its largest joint step ``size`` [rad] and the
    constraints ``held`` for it."""

    merit: np.ndarray
    q: np.ndarray
    size: float
    held: _Held


@dataclass(frozen=True)
class _Level:
    """One priority level as the sweep sees it: its ``rows`` in the stacked residual, its
    damping λ [task units] and either its Jacobian (a view of the evaluation buffer) or,
    when every task is a joint reference, the DOF each row ``selects`` (J_k a selection
    matrix), with ``identity`` when that takes every DOF once (J_k = I up to row order)."""

    rows: slice
    damping: float
    jacobian: np.ndarray | None = None
    selects: np.ndarray | None = None
    identity: bool = False


#: The held constraints are tested for release (``NullspaceSolver._held_step``) on the
#: first iteration and every ``RETEST``-th after it, besides when they grow, when an
#: iteration brings no progress and at rest. Every 2nd, 4th or 8th iteration gave the same
#: iteration counts from warm starts on the benchmark humanoids; every 8th doubled them from
#: the 28-DOF upright start (117 against 64), where the first steps hold many joints that
#: the tasks soon pull back.
RETEST = 4

#: In ``NullspaceSolver.solve`` (``NullspaceSolver.iteration`` is the paper's loop)
#: the clamping loop holds, of the free joints a step takes beyond a limit and the inequality
#: if it violates it, those the step reaches first: a constraint at its bound already
#: (within ``ACTIVE_TOLERANCE``) is reached at once, the others at the fraction of the step
#: where they cross; those reached within ``FIRST_REACHED`` times the first are held, the
#: step is swept again, and what it still takes beyond is held on the next pass (Baerlocher
#: and Boulic's loop holds every violator of a pass at once; the SNS algorithm of Flacco, De
#: Luca and Khatib saturates the first). A constraint that the others, once held, keep inside
#: is then never held. Measured on the 28-DOF benchmark body (a step of its 20-minute
#: simulation; 29 of its 1201 steps fell back on the other solver): the step, with the
#: constraint on the right leg held, takes three joints at their limits beyond and the right
#: hip rotation at 0.81 of its length; holding all four moved the hip rotation 0.52 rad onto
#: its lower limit, to a rest with the ankles 0.2389 m off, worse than the 0.2224 m passed:
#: ``stalled``. Holding the three first, the hip rotation stays inside, and the run converges
#: to the lexicographic solver's answer (0.2222972 m, the same joints at their limits). The
#: factor: steps far outside the linear range reach several constraints at nearly the same
#: fraction, an order the linearisation cannot tell. Measured on the 2-DOF arm under the
#: paper's -45° line (holding_m45.toml, at 215 s): a 2.4 rad step along the held constraint
#: reaches the shoulder's lower limit at 0.354 of its length and the elbow's at 0.379;
#: holding the shoulder alone left the arm at the corner of its limit and the constraint,
#: the wrist 0.61 m off the line (the lexicographic solver: 0.019 m), called converged, and
#: the arm exhausted at 284 s instead of 328 s. Any factor from 1.1 to 4 gives the same
#: simulations of that arm and of the 28-DOF body (7 and 0 fallbacks); the first alone
#: (factor 1) gives 12 on the arm, and holding everything past those at their bounds at once
#: 28 on the 28-DOF body.
FIRST_REACHED = 2.0

#: The iteration is accelerated while its step shrinks by less than this factor per
#: iteration (slow linear convergence; faster contraction is left alone) and is shorter
#: than ``ACCELERATED_STEP`` [rad]. Longer steps are shaped by the task error clamping and
#: the joint limits rather than by a smooth contraction: a 2-DOF arm cruising towards an
#: unreachable target at 0.18 rad per step, its step shrinking by 0.5 %, was extrapolated
#: 170° across its range.
SLOW_CONTRACTION = 0.5
ACCELERATED_STEP = 0.01


class _Anderson:
    """Anderson acceleration (type II; Walker & Ni 2011) of the fixed-point iteration
    q ← G(q), G one Baerlocher-Boulic iteration.

    Near a solution the iteration converges linearly: each level is linearised without the
    curvature of the levels above, which a lower level in conflict with them feels in
    proportion to its residual. Rates of 0.87 to 0.99 per iteration were measured on the
    benchmark humanoids (7 to 42 DOF), that is 120 to 1000 iterations to a 1e-10 rad step.
    From the last ``memory`` steps f_j = G(q_j) - q_j and values G(q_j), the next posture
    is G(q_k) - ΔG γ with γ minimising ‖f_k - ΔF γ‖ (Δ: differences of successive
    iterates): a secant step on the fixed-point equation, 10 to 35 iterations on those
    bodies, to the same fixed point. Safeguards: it acts only while the step shrinks
    slowly (``SLOW_CONTRACTION``) and is short (``ACCELERATED_STEP``); it forgets its
    memory when the step grows or the held constraints change (the iteration is then
    another smooth map), and an extrapolated posture at which they change is abandoned for
    the plain iterate G(q_k) it came from (overshooting a solution at a joint limit can
    release the joint where the plain iteration would not).
    """

    def __init__(self, memory: int) -> None:
        self.memory = memory
        self._plain: np.ndarray | None = None
        self.abandon()

    def abandon(self) -> np.ndarray | None:
        """Forget the memory; return the plain iterate G(q_k) if the last posture was
        extrapolated from it (to go back to), else None."""
        plain, self._plain = self._plain, None
        self._f: list[np.ndarray] = []
        self._g: list[np.ndarray] = []
        self._last: tuple[np.ndarray, np.ndarray, float] | None = None
        return plain

    def __call__(self, q: np.ndarray, g: np.ndarray) -> np.ndarray:
        """The next posture [rad] after ``q``, from the iteration's ``g`` = G(q)."""
        f = g - q
        size = float(np.abs(f).max())
        last, self._last, self._plain = self._last, (f, g, size), None
        if last is None or self.memory == 0:
            return g
        f0, g0, size0 = last
        if size >= size0:
            self._f, self._g = [], []
            return g
        self._f = [*self._f, f - f0][-self.memory :]
        self._g = [*self._g, g - g0][-self.memory :]
        if size <= SLOW_CONTRACTION * size0 or size > ACCELERATED_STEP:
            return g
        self._plain = g
        gamma = np.linalg.lstsq(np.array(self._f).T, f, rcond=None)[0]
        return g - np.array(self._g).T @ gamma


class NullspaceSolver:
    """Prioritized IK by nullspace projection on a task hierarchy; build once, solve often.

    An instance evaluates its CasADi function in buffers it owns: use one per thread.
    """

    name = "nullspace"

    def __init__(self, hierarchy: TaskHierarchy, options: NullspaceOptions | None = None) -> None:
        self.hierarchy = hierarchy
        self.options = options or NullspaceOptions()
        body = hierarchy.body
        self._lower, self._upper, self._eye = body.lower, body.upper, np.eye(body.n)
        slack = self.options.limit_slack
        self._lower_slack, self._upper_slack = self._lower - slack, self._upper + slack
        tasks = [(t, rows) for blocks in hierarchy.blocks for t, rows in blocks]
        sizes = [rows.stop - rows.start for _, rows in tasks]
        self._task_of_row = np.repeat(np.arange(len(tasks)), sizes)
        self._merit_of_row = np.repeat(np.arange(1, hierarchy.depth + 1), hierarchy.sizes)
        self._step_limits = np.array([t.step_limit for t, _ in tasks])
        self._evaluate = self._build()
        # κ_k per level while solve() runs; none on level 1, which no task constrains
        self._base_floor = [0.0] + [self.options.curvature] * (hierarchy.depth - 1)
        self._floor: list[float] | None = None
        self._ordered = False  # whether the clamping loop holds first what it reaches first

    def _build(self) -> Callable[[], None]:
        """The levels, and the evaluation of every e_k then the column-major J_k of the
        levels that are not selections, as one dense output in a buffer (zero-copy
        ``Function.buffer``). CasADi's common-subexpression elimination is not asked for:
        it took 0.36 s to build at 29 DOF and 0.17 s at 42 and evaluated no faster."""
        h, n = self.hierarchy, self.hierarchy.body.n
        selections = [self._selection(k) for k in range(h.depth)]
        jacobians = [
            ca.vec(ca.densify(j)) for j, s in zip(h.jacobians, selections, strict=True) if s is None
        ]
        function = ca.Function(
            "nullspace_point",
            [h.body.q, h.p],
            [ca.vertcat(*h.residuals, *jacobians)],
        )
        self._q, self._p = np.zeros(n), np.array(h.targets, dtype=float)
        self._fresh = False  # whether the buffer holds the evaluation at self._q
        self._out = np.zeros(function.nnz_out(0))
        self._buffer, evaluate = function.buffer()  # kept: the buffer must outlive its use
        self._buffer.set_arg(0, memoryview(self._q))
        self._buffer.set_arg(1, memoryview(self._p))
        self._buffer.set_res(0, memoryview(self._out))
        self._errors = self._out[: sum(h.sizes)]
        self._levels, row, offset = [], 0, self._errors.size
        for k, (m, selects) in enumerate(zip(h.sizes, selections, strict=True)):
            rows, row = slice(row, row + m), row + m
            d = self.options.damping
            damping = float(d if isinstance(d, float | int) else d[k])
            if selects is not None:
                identity = np.array_equal(np.sort(selects), np.arange(n))
                self._levels.append(_Level(rows, damping, selects=selects, identity=identity))
                continue
            jacobian = self._out[offset : offset + m * n].reshape((m, n), order="F")
            offset += m * n
            self._levels.append(_Level(rows, damping, jacobian))
        return evaluate

    def rebind(self, hierarchy: TaskHierarchy) -> NullspaceSolver:
        """This solver on ``hierarchy``, of the same structure (other target values): the
        compiled function and its buffers are shared (use both in one thread); nothing of
        earlier solves is kept."""
        other = copy.copy(self)
        other.hierarchy = hierarchy
        return other

    def _selection(self, k: int) -> np.ndarray | None:
        """The DOF each row of level k selects when all its tasks are joint references."""
        tasks = [t for t, _ in self.hierarchy.blocks[k]]
        if not all(isinstance(t, JointReference) for t in tasks):
            return None
        index = self.hierarchy.body.index
        return np.array([index[d] for t in tasks for d in t.dofs], dtype=int)

    def _targets(self) -> None:
        """Put the hierarchy's targets in the buffer (nothing evaluated with them yet)."""
        self._p[:] = self.hierarchy.targets
        self._fresh = False

    def _point(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Evaluate at ``q`` [rad]: (0, ‖e_1‖, …, ‖e_L‖), and Δx = -e stacked, each task's
        part scaled down to its step limit (the Jacobians are left in the buffer). The buffer
        is reused when it holds ``q`` already: a converged solve's checks and its residuals
        are at the posture its last iteration evaluated."""
        if not (self._fresh and np.array_equal(q, self._q)):
            self._q[:] = q
            self._evaluate()
            self._fresh = True
        e = self._errors
        square = e * e
        tasks = np.sqrt(np.bincount(self._task_of_row, square, self._step_limits.size))
        scale = np.minimum(1.0, self._step_limits / np.maximum(tasks, _TINY))
        norms = np.sqrt(np.bincount(self._merit_of_row, square, len(self._levels) + 1))
        return norms, -e * scale[self._task_of_row]

    def _sweep(
        self, q: np.ndarray, dx: np.ndarray, inequality: Inequality | None, held: _Held
    ) -> np.ndarray:
        """Δq [rad] of the priority sweep towards Δx with the ``held`` constraints (and the
        damping floor ``self._floor`` while ``solve`` runs)."""
        tol, n, side = self.options.rank_tolerance, q.size, held.side
        floor = self._floor
        dq, basis = np.zeros(n), None  # None: Z = I, every joint free
        if side is not None:
            dq = np.where(side < 0, self._lower - q, 0.0) + np.where(side > 0, self._upper - q, 0.0)
            basis = self._eye[:, side == 0]
        steps = [(dx[level.rows], level, k) for k, level in enumerate(self._levels)]
        if held.inequality:
            assert inequality is not None
            hard = _Level(slice(0, 1), 0.0, inequality.a[None, :])
            steps.insert(0, (np.array([inequality.b - inequality.a @ q]), hard, 0))
        for target, level, k in steps:
            free = n if basis is None else basis.shape[1]
            if free == 0:
                break
            if level.identity:  # J̃ = P: singular values 1, no floor
                full = np.empty(n)
                full[level.selects] = target
                step = full - dq
                dq += (step if basis is None else basis @ (basis.T @ step)) / (1 + level.damping**2)
                break
            if level.jacobian is None:
                jt = self._eye[level.selects] if basis is None else basis[level.selects]
                residual = target - dq[level.selects]
            else:
                jt = level.jacobian if basis is None else level.jacobian @ basis
                residual = target - level.jacobian @ dq
            # the floor μ = κ_k ‖r_k‖ (none on level 1 and the inequality: κ_0 = 0)
            mu = floor[k] * math.sqrt(residual.dot(residual)) if floor and k else 0.0
            if free == 1:  # J̃ is one column c: Δq += z cᵀr / (cᵀc + λ²), nothing left free
                c = jt[:, 0]
                square = float(c @ c)
                if square <= tol * tol:
                    continue
                z = self._eye[:, 0] if basis is None else basis[:, 0]
                dq += z * (float(c @ residual) / (max(square, mu) + level.damping**2))
                break
            u, s, vt = _svd(jt)
            rank = int(np.count_nonzero(s > tol))
            if rank == 0:
                continue
            s = s[:rank]
            square = s * s
            along = u[:, :rank].T @ residual
            lifted = mu > square  # s is sorted: the floor lifts the smallest ones
            if lifted[-1]:
                square = np.maximum(square, mu)
            step = vt[:rank].T @ (along * (s / (square + level.damping**2)))
            dq += step if basis is None else basis @ step
            if lifted[-1] and _out_of_reach(along, lifted, residual):
                break  # level k at rest out of reach: the levels below wait
            basis = vt[rank:].T if basis is None else basis @ vt[rank:].T
        return dq

    def _caught(
        self, q: np.ndarray, dq: np.ndarray, inequality: Inequality | None, held: _Held
    ) -> _Held | None:
        """``held`` with the free joints the step Δq [rad] takes more than ``limit_slack``
        beyond a limit and the inequality if it violates it (while ``solve`` runs, those
        it reaches first: ``_first_reached``); None when it takes nothing new beyond."""
        after, free = q + dq, True if held.side is None else held.side == 0
        below = free & (after < self._lower_slack)
        above = free & (after > self._upper_slack)
        violated = (
            inequality is not None
            and not held.inequality
            and float(inequality.a @ after) > inequality.b + self.options.limit_slack
        )
        joints = bool(below.any() or above.any())
        if not (violated or joints):
            return None
        if self._ordered:
            below, above, violated = self._first_reached(q, dq, inequality, below, above, violated)
            joints = bool(below.any() or above.any())
        side = held.side
        if joints:
            side = np.zeros(q.size, dtype=int) if side is None else side.copy()
            side[below], side[above] = -1, 1
        return _Held(side, held.inequality or violated)

    def _first_reached(
        self,
        q: np.ndarray,
        dq: np.ndarray,
        inequality: Inequality | None,
        below: np.ndarray,
        above: np.ndarray,
        violated: bool,
    ) -> tuple[np.ndarray, np.ndarray, bool]:
        """Of the joints the step Δq [rad] takes ``below`` or ``above`` their limits and the
        inequality if ``violated``, those it reaches within ``FIRST_REACHED`` times the
        first."""
        # the fraction of the step at which each is reached: 0 at its bound already
        reach = np.full(q.size, np.inf)
        reach[below] = (self._lower[below] - q[below]) / dq[below]
        reach[above] = (self._upper[above] - q[above]) / dq[above]
        reach[below & (q <= self._lower + ACTIVE_TOLERANCE)] = 0.0
        reach[above & (q >= self._upper - ACTIVE_TOLERANCE)] = 0.0
        ineq_reach = np.inf
        if violated:
            assert inequality is not None
            gap = inequality.b - float(inequality.a @ q)
            ineq_reach = 0.0 if gap <= ACTIVE_TOLERANCE else gap / float(inequality.a @ dq)
        first = FIRST_REACHED * min(float(reach.min()), ineq_reach)
        return below & (reach <= first), above & (reach <= first), violated and ineq_reach <= first

    def _clamped_step(
        self, q: np.ndarray, dx: np.ndarray, inequality: Inequality | None, held: _Held
    ) -> tuple[np.ndarray, _Held]:
        """Sweep, hold what the step takes (first) beyond its limit, sweep again: until the
        held set stops growing (each pass holds one more joint or the inequality, so at most
        n + 2 sweeps)."""
        while True:
            dq = self._sweep(q, dx, inequality, held)
            more = self._caught(q, dq, inequality, held)
            if more is None:
                return dq, held
            held = more

    def _held_step(
        self,
        q: np.ndarray,
        dx: np.ndarray,
        inequality: Inequality | None,
        held: _Held,
        test: bool,
    ) -> tuple[np.ndarray, _Held]:
        """Δq [rad] and the constraints held for it, starting from those ``held`` before.

        Baerlocher and Boulic's clamping loop starts every iteration with nothing held and
        holds what the step, recomputed after each clamp, takes beyond its limit: pass
        after pass, a sweep each. Here the held set is carried from one iteration to the
        next; the loop adds to it what the step takes beyond a limit, and while it does not
        grow an iteration costs one sweep.

        Release, when ``test`` (see ``RETEST``), when the held set grew, and at rest (step
        below ``tolerance``): the loop's own first pass, the step with nothing held, says
        where the tasks pull. A held constraint stays held unless that step pulls it back
        inside its range (Δq_i > 0 at a lower limit, < 0 at an upper one, aᵀΔq < 0 for the
        inequality); what that step takes (first) beyond a limit is held too, and the loop
        goes on from there. So a constraint is held against the pull of the tasks for at most
        ``RETEST`` - 1 iterations, and a converged posture is a fixed point of the loop: at
        rest, the loop restarted from nothing holds the same set.
        """
        if held and not test:
            dq, now = self._clamped_step(q, dx, inequality, held)
            if now.same(held) and np.abs(dq).max() >= self.options.tolerance:
                return dq, now
        free = self._sweep(q, dx, inequality, _NOTHING)
        caught = self._caught(q, free, inequality, _NOTHING)
        kept = self._pushed(q, free, inequality, held)
        if caught is None and not kept:
            return free, _NOTHING
        return self._clamped_step(q, dx, inequality, kept.union(caught))

    def _pushed(
        self, q: np.ndarray, dq: np.ndarray, inequality: Inequality | None, held: _Held
    ) -> _Held:
        """The constraints of ``held`` that the step Δq [rad] does not pull inside."""
        side = held.side
        if side is not None:
            side = np.where(side * dq >= 0.0, side, 0)
            side = side if side.any() else None
        keep = held.inequality and inequality is not None and float(inequality.a @ dq) >= 0.0
        return _Held(side, keep)

    def _iterate(
        self, q: np.ndarray, inequality: Inequality | None, held: _Held, test: bool = True
    ) -> _Step:
        """One iteration from ``q`` [rad] with ``held`` carried from the last, tested for
        release when ``test``."""
        merit, dx = self._point(q)
        merit[0] = 0.0 if inequality is None else inequality.violation(q)
        dq, held = self._held_step(q, dx, inequality, held, test)
        q_next = np.minimum(np.maximum(q + dq, self._lower), self._upper)
        return _Step(merit, q_next, float(np.abs(q_next - q).max()), held)

    def iteration(self, q: np.ndarray, inequality: Inequality | None = None) -> np.ndarray:
        """The posture [rad] one iteration takes ``q`` to, with nothing held before it (the
        original clamping loop; no acceleration)."""
        self._targets()
        return self._iterate(np.asarray(q, dtype=float), inequality, _NOTHING).q

    def solve(
        self,
        q0: np.ndarray,
        inequality: Inequality | None = None,
        *,
        max_iterations: int | None = None,
    ) -> IKResult:
        """Iterate from ``q0`` [rad] until the largest joint step is below the tolerance."""
        start = time.perf_counter()
        body = self.hierarchy.body
        if inequality is not None:
            inequality = Inequality(np.asarray(inequality.a, dtype=float), float(inequality.b))
        self._targets()
        limit = max_iterations or self.options.max_iterations
        q = np.clip(np.asarray(q0, dtype=float), body.lower, body.upper)
        self._floor = list(self._base_floor) if self.options.curvature > 0 else None
        self._ordered = True
        try:
            q, status, iterations = self._iterations(q, inequality, limit)
            q, status, iterations = self._leave_saddles(q, status, iterations, inequality, limit)
        finally:
            self._floor, self._ordered = None, False
        residuals = self._point(q)[0][1:]
        at_limits, active = active_constraints(body, q, inequality)
        hard_ok = inequality is None or inequality.violation(q) <= 1e-9
        return IKResult(
            solver=self.name,
            q=q,
            residuals=residuals,
            iterations=iterations,
            status=status if hard_ok else f"{status}; inequality violated",
            success=status == "converged" and hard_ok,
            at_limits=at_limits,
            inequality_active=active,
            wall_time_s=time.perf_counter() - start,
        )

    def _iterations(
        self, q: np.ndarray, inequality: Inequality | None, limit: int, held: _Held = _NOTHING
    ) -> tuple[np.ndarray, str, int]:
        """The iterations of ``solve`` from ``q`` [rad] with ``held`` held for the first
        (untested): the posture, status, count."""
        accelerate = _Anderson(self.options.acceleration_memory)
        status, iterations, best, since = "max_iterations", 0, None, 0
        best_q, shortest = q.copy(), np.inf
        last = None
        while iterations < limit:
            iterations += 1
            test = since > 0 or (iterations % RETEST == 1 and not (iterations == 1 and held))
            merit, q_next, step, now = self._iterate(q, inequality, held, test)
            if not now.same(held):
                back = accelerate.abandon()
                if back is not None:  # the extrapolation left the smooth piece it came from
                    q = back
                    continue
            held = now
            last = self._adapt_floor(q_next - q, last) if step >= ACCELERATED_STEP else None
            if best is None or _better(merit, best, PROGRESS_MARGIN):
                best, best_q, since, shortest = merit, q.copy(), 0, step
            elif step < STEP_PROGRESS * shortest:
                since, shortest = 0, step
            else:
                since += 1
            if step < self.options.tolerance:
                q = q_next
                worse = _better(best, merit, REST_MARGIN)
                far = float(np.abs(best_q - q).max()) > REST_DISTANCE
                status = "stalled" if worse and far else "converged"
                break
            if since >= self.options.stall_iterations:
                status = "stalled"
                break
            q = accelerate(q, q_next)
            if q is not q_next:
                q = np.minimum(np.maximum(q, self._lower), self._upper)
        return (q if status == "converged" else best_q), status, iterations

    def _leave_saddles(
        self,
        q: np.ndarray,
        status: str,
        iterations: int,
        inequality: Inequality | None,
        limit: int,
    ) -> tuple[np.ndarray, str, int]:
        """Restart a converged run that rests on a saddle of its first missed level (see
        ``STATIONARY``) from a posture that leaves it; keep the better rest. A saddle that no
        restart leaves, or a rest where that level could still go lower (``KKT_TOLERANCE``),
        is no answer: its status says which level and how far off it is [task units]."""
        restarts = 0
        while status == "converged":
            found = self._saddle(q, inequality) or self._unbalanced(q, inequality)
            if found is None:
                break
            k, start, held, why = found
            if start is not None and restarts < SADDLE_RESTARTS and iterations < limit:
                restarts += 1
                q_next, status_next, spent = self._iterations(
                    start, inequality, limit - iterations, held
                )
                iterations += spent
                merit, before = self._merit(q_next, inequality), self._merit(q, inequality)
                if status_next == "converged" and _better(merit, before, REST_MARGIN):
                    q = q_next
                    continue
            residual = self._point(q)[0][k + 1]
            status = f"stalled: level {k + 1} {why}, residual {residual:.3g}"
        return q, status, iterations

    def _merit(self, q: np.ndarray, inequality: Inequality | None) -> np.ndarray:
        """(inequality violation, ‖e_1‖, …, ‖e_L‖) at ``q`` [rad]."""
        merit = self._point(q)[0]
        merit[0] = 0.0 if inequality is None else inequality.violation(q)
        return merit

    def _unbalanced(
        self, q: np.ndarray, inequality: Inequality | None
    ) -> tuple[int, np.ndarray, _Held, str] | None:
        """The first level k missed at ``q`` [rad] when a joint limit or the inequality held
        there keeps it from going lower, its gradient outside the KKT cone (see
        ``KKT_TOLERANCE``), with ``q`` and the constraints active there less the one whose
        multiplier is most negative, to restart from; None otherwise."""
        lower = q <= self._lower + ACTIVE_TOLERANCE
        upper = q >= self._upper - ACTIVE_TOLERANCE
        joints = [*np.flatnonzero(upper), *np.flatnonzero(lower)]
        normals = [self._eye[:, i] * (1.0 if upper[i] else -1.0) for i in joints]
        active = inequality is not None and inequality.a @ q >= inequality.b - ACTIVE_TOLERANCE
        if active:
            normals.append(inequality.a)
        norms = self._point(q)[0]
        missed = np.flatnonzero(norms[1:] > ACHIEVED_TOLERANCE)
        if not normals or missed.size == 0:
            return None  # nothing held: a fixed point of the sweep is stationary
        k = int(missed[0])
        jacobian = self._jacobian(k)
        gradient = jacobian.T @ self._errors[self._levels[k].rows]
        if k:  # the levels above are equalities: their row space is left out
            _, s, vt = np.linalg.svd(np.vstack([self._jacobian(j) for j in range(k)]))
            kept = vt[int(np.count_nonzero(s > SADDLE_RANK * s[0])) :].T
            gradient, normals = kept.T @ gradient, [kept.T @ v for v in normals]
        cone = np.array(normals).T
        remainder = gradient + cone @ _nnls(cone, -gradient)
        scale = float(np.linalg.norm(jacobian) * norms[k + 1])
        if np.linalg.norm(remainder) <= KKT_TOLERANCE * scale:
            return None
        side = np.where(upper, 1, 0) - np.where(lower, 1, 0)
        drop = int(np.argmin(np.linalg.lstsq(cone, -gradient, rcond=None)[0]))
        if drop < len(joints):
            side[joints[drop]] = 0
        held = _Held(side if side.any() else None, active and drop < len(joints))
        return k, q, held, "held at a limit it pulls away from"

    def _saddle(
        self, q: np.ndarray, inequality: Inequality | None
    ) -> tuple[int, np.ndarray, _Held, str] | None:
        """The first level missed at ``q`` [rad] and a posture that lowers its residual along
        a direction of negative curvature (to restart from with nothing held), when ``q`` is a
        saddle of that level (see ``STATIONARY``); None otherwise."""
        norms = self._point(q)[0]
        missed = np.flatnonzero(norms[1:] > ACHIEVED_TOLERANCE)
        if missed.size == 0 or self._levels[missed[0]].jacobian is None:
            return None  # nothing missed, or a level of joint references: linear, no saddle
        k = int(missed[0])
        level = self._levels[k]
        e, jacobian = self._errors[level.rows], level.jacobian
        gradient = jacobian.T @ e
        lower = q <= self._lower + ACTIVE_TOLERANCE
        upper = q >= self._upper - ACTIVE_TOLERANCE
        gradient[(lower & (gradient > 0.0)) | (upper & (gradient < 0.0))] = 0.0  # the limit holds
        rows = [self._jacobian(j) for j in range(k + 1)]
        if inequality is not None and inequality.a @ q >= inequality.b - ACTIVE_TOLERANCE:
            a = inequality.a
            if gradient @ a < 0.0:  # descent would break the inequality: it holds that part
                gradient -= (gradient @ a) / (a @ a) * a
            rows.append(a[None, :])
        scale = float(np.linalg.norm(jacobian) * np.linalg.norm(e))
        if np.linalg.norm(gradient) > STATIONARY * scale:
            return None  # a higher level, a limit or the inequality holds it off: a conflict
        _, s, vt = np.linalg.svd(np.vstack(rows))
        rank = int(np.count_nonzero(s > SADDLE_RANK * s[0])) if s.size else 0
        free = vt[rank:].T
        if free.shape[1] == 0:
            return None
        value, direction = np.linalg.eigh(self._curvature(q, k, free))
        if value[0] >= 0.0:
            return None  # a minimum of the level (a target out of reach): the best it can
        move = free @ direction[:, 0]
        for size in SADDLE_STEPS:
            for sign in (1.0, -1.0):
                start = np.clip(q + sign * size * move, self._lower, self._upper)
                if self._point(start)[0][k + 1] < norms[k + 1] * (1.0 - REST_MARGIN[0]):
                    return k, start, _NOTHING, "at a saddle"
        return None

    def _jacobian(self, k: int) -> np.ndarray:
        """A copy of J_k at the last evaluated posture (selection levels: rows of I)."""
        level = self._levels[k]
        if level.jacobian is None:
            return self._eye[level.selects]
        return level.jacobian.copy()

    def _curvature(self, q: np.ndarray, k: int, free: np.ndarray) -> np.ndarray:
        """The Hessian of ‖e_k‖² at ``q`` [rad] in the coordinates y of q + free·y, by central
        differences of ``SADDLE_PROBE`` (r(r + 1) evaluations for r columns of ``free``)."""
        h, r = SADDLE_PROBE, free.shape[1]
        f0 = self._point(q)[0][k + 1] ** 2

        def second(v: np.ndarray) -> float:
            up, down = self._point(q + h * v)[0][k + 1], self._point(q - h * v)[0][k + 1]
            return (up * up + down * down - 2.0 * f0) / (h * h)

        hessian = np.diag([second(free[:, i]) for i in range(r)])
        for i in range(r):
            for j in range(i + 1, r):
                mixed = second(free[:, i] + free[:, j])
                hessian[i, j] = hessian[j, i] = (mixed - hessian[i, i] - hessian[j, j]) / 2.0
        return hessian

    def _adapt_floor(self, move: np.ndarray, last: np.ndarray | None) -> np.ndarray | None:
        """Raise the damping floor below level 1 when the iteration's ``move`` [rad] turns
        back on the ``last`` one (``REVERSAL``), lower it back towards κ when they agree;
        the move to compare the next with (None without a floor)."""
        floor = self._floor
        if floor is None:
            return None
        if last is not None:
            turn = float(move @ last) / math.sqrt(float((move @ move) * (last @ last)))
            base = self._base_floor
            if turn < -REVERSAL:
                floor[:] = [
                    min(f * FLOOR_RAISE, b * FLOOR_CAP) for f, b in zip(floor, base, strict=True)
                ]
            elif turn > 0.0:
                floor[:] = [max(f / FLOOR_LOWER, b) for f, b in zip(floor, base, strict=True)]
        return move
