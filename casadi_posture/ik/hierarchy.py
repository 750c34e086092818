"""Tasks grouped into strict priority levels, with every residual and Jacobian in one
compiled CasADi call; and the linear inequality ``aᵀq ≤ b`` that sits above them."""

from __future__ import annotations

import copy
import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from casadi_posture.body.tree import BodyModel
from casadi_posture.compiled import Compiled
from casadi_posture.errors import ProblemError
from casadi_posture.ik.tasks import Comfort, JointReference, Task


@dataclass(frozen=True)
class Inequality:
    """The hard constraint aᵀq ≤ b (q [rad]); ``a`` is normalised by the caller if wanted."""

    a: np.ndarray
    b: float

    def violation(self, q: np.ndarray) -> float:
        """max(0, aᵀq - b)."""
        return max(0.0, float(self.a @ q - self.b))


class TaskHierarchy:
    """Priority levels of tasks on one body.

    ``levels[k]`` lists the tasks of level k+1 (tasks sharing a priority are
    stacked); ``residuals[k]`` and ``jacobians[k]`` are their SX expressions in
    ``body.q`` and the target vector ``p``; ``function(q, p)`` returns
    ``e_1, …, e_L, J_1, …, J_L`` in one call.

    On a body whose numbers are the symbols of a ``Shape`` (``shape``, with their values for
    the person the tasks are built for) those symbols follow the tasks' parameters in ``p``
    and their values follow the targets: ``rebound`` gives the hierarchy of another person
    without building anything.
    """

    def __init__(
        self,
        body: BodyModel,
        tasks: Sequence[Task],
        shape: tuple[ca.SX, np.ndarray] | None = None,
    ) -> None:
        if not tasks:
            raise ProblemError(None, "tasks", [], "at least one task to solve")
        self.body = body
        priorities = sorted({t.priority for t in tasks})
        self.priorities = priorities
        self.levels = [[t for t in tasks if t.priority == p] for p in priorities]
        values = [t.targets() for level in self.levels for t in level]
        own = np.concatenate(values) if values else np.zeros(0)
        symbols, numbers = shape if shape is not None else (ca.SX(0, 1), np.zeros(0))
        self.targets = np.concatenate([own, numbers])
        self._shape_size = numbers.size
        self.p = ca.vertcat(ca.SX.sym("targets", own.size), symbols)
        self.residuals: list[ca.SX] = []
        self.blocks: list[list[tuple[Task, slice]]] = []
        self._offsets: dict[str, int] = {}
        offset = 0
        for level in self.levels:
            parts, blocks, row = [], [], 0
            for task in level:
                size = task.targets().size
                self._offsets[task.name] = offset
                e = task.residual(body, self.p[offset : offset + size])
                offset += size
                parts.append(e)
                blocks.append((task, slice(row, row + e.numel())))
                row += e.numel()
            self.residuals.append(ca.vertcat(*parts))
            self.blocks.append(blocks)
        self.jacobians = [ca.jacobian(e, body.q) for e in self.residuals]
        self._compile()

    def _compile(self) -> None:
        """``function`` of the levels' residuals and Jacobians, in one call."""
        self._residuals: Compiled | None = None
        self.sizes = [e.numel() for e in self.residuals]
        self.function = ca.Function(
            "levels",
            [self.body.q, self.p],
            self.residuals + self.jacobians,
            ["q", "targets"],
            [f"e{k + 1}" for k in range(len(self.levels))]
            + [f"J{k + 1}" for k in range(len(self.levels))],
        )

    def subset(self, keep: Sequence[int]) -> TaskHierarchy:
        """The hierarchy of the levels ``keep`` (indices, in order) of this one, their
        parameters and the shape's in ``p``: its expressions are this one's (nothing is
        differentiated again), one function is compiled."""
        other = copy.copy(self)
        for name in ("levels", "priorities", "residuals", "jacobians", "blocks"):
            setattr(other, name, [getattr(self, name)[k] for k in keep])
        pieces, targets, other._offsets, offset = [], [], {}, 0
        for task in (t for level in other.levels for t in level):
            start, size = self._offsets[task.name], task.targets().size
            other._offsets[task.name], offset = offset, offset + size
            pieces.append(self.p[start : start + size])
            targets.append(self.targets[start : start + size])
        tail = self.targets.size - self._shape_size
        other.p = ca.vertcat(*pieces, self.p[tail:])
        other.targets = np.concatenate([*targets, self.targets[tail:]])
        other._compile()
        return other

    def copy(self) -> TaskHierarchy:
        """The same compiled hierarchy with target values of its own (a run sets some in
        place: the whole-body adjustment's effort weights)."""
        other = copy.copy(self)
        other.targets = self.targets.copy()
        return other

    def rebound(self, tasks: Sequence[Task], shape: np.ndarray) -> TaskHierarchy:
        """This compiled hierarchy for another person: ``tasks`` of the same names and sizes
        as its own (they replace its own, their targets taken) and the values of its shape's
        symbols."""
        other = copy.copy(self)
        own = {t.name: t for t in tasks}
        other.levels = [[own[t.name] for t in level] for level in self.levels]
        other.blocks = [[(own[t.name], rows) for t, rows in level] for level in self.blocks]
        values = [t.targets() for level in other.levels for t in level]
        other.targets = np.concatenate([*values, shape])
        if other.targets.size != self.targets.size:
            raise ValueError(f"{other.targets.size} target values for {self.targets.size}")
        return other

    def shape_values(self) -> np.ndarray:
        """The values of the shape's symbols in ``targets`` (none without a shape)."""
        return self.targets[self.targets.size - self._shape_size :]

    def offset(self, task: Task) -> int:
        """Where ``task``'s parameters start in ``targets``."""
        return self._offsets[task.name]

    @property
    def depth(self) -> int:
        """Number of priority levels."""
        return len(self.levels)

    def level_names(self) -> list[str]:
        """'+'-joined task names of each level."""
        return ["+".join(t.name for t in level) for level in self.levels]

    def level_units(self) -> list[str]:
        """Unit of each level's residual: 'm', 'rad' or 'm, rad' for a mixed level."""
        return [", ".join(sorted({t.unit for t in level}, reverse=True)) for level in self.levels]

    def criterion_level(self) -> int | None:
        """The index of the last level when it only settles what the tasks leave free
        (comfort or joint-reference tasks: minimised, never expected to reach zero); None
        otherwise."""
        last = self.levels[-1]
        if len(self.levels) > 1 and all(isinstance(t, Comfort | JointReference) for t in last):
            return len(self.levels) - 1
        return None

    def free_dofs(self, q: np.ndarray) -> int:
        """DOFs no level determines at ``q`` [rad]: n − rank of all levels' Jacobians. Each
        solver settles them its own way unless a posture task at the lowest level does."""
        out = self.function(q, self.targets)
        stacked = np.vstack([np.asarray(j) for j in out[self.depth :]])
        return self.body.n - int(np.linalg.matrix_rank(stacked, tol=1e-9))

    def residual_norms(self, q: np.ndarray) -> np.ndarray:
        """‖e_k(q)‖ of every level (task units), by a compiled call of the residuals alone
        (built at the first call; one hierarchy per thread)."""
        if self._residuals is None:
            stacked = ca.densify(ca.vertcat(*self.residuals))
            self._residuals = Compiled(
                ca.Function("residuals", [self.body.q, self.p], [stacked], ["q", "p"], ["e"])
            )
        e = self._residuals(q=q, p=self.targets)["e"]
        ends = np.cumsum([0, *self.sizes])
        return np.array([np.linalg.norm(e[a:b]) for a, b in itertools.pairwise(ends)])
