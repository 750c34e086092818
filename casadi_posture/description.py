"""The resolved model of a problem as plain data (``casadi-posture describe``)."""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from casadi_posture.problem import Problem


def _zero_posture(problem: Problem, expression: ca.SX) -> list[float]:
    value = ca.Function("f", [problem.body.q], [expression])(np.zeros(problem.body.n))
    return [round(float(v), 12) for v in np.asarray(value).reshape(-1)]


def description(problem: Problem) -> dict[str, Any]:
    """DOFs, segments, landmarks, loads, half-joints, tasks, settings and parameters.

    Positions are in the world frame at the zero posture [m], ranges in degrees. ``dofs``,
    ``segments``, ``landmarks`` and ``feet`` are the body's tree as a problem file writes it
    (``body.tree``), whether the file gave one or named a built-in model.
    """
    body = problem.body
    spec = problem.spec
    return {
        "problem": str(problem.path),
        "title": problem.heading,
        "notes": list(problem.notes),
        "model": body.name,
        "sex": spec.body.sex,
        "stature_m": spec.body.stature_m,
        "body_mass_kg": spec.body.mass_kg,
        "gravity_m_s2": body.gravity,
        **{
            table: [item.model_dump(exclude_none=True) for item in getattr(problem.tree, table)]
            for table in ("dofs", "segments", "landmarks", "feet")
        },
        "loads": [
            {
                "name": load.name,
                "at": load.at,
                "point_m": _zero_posture(problem, body.landmark(load.at)),
                "dof": body.landmarks[load.at].dof,
                "mass_kg": load.mass,
                "force_N": list(load.force),
                "moment_Nm": list(load.moment),
            }
            for load in problem.loads
        ],
        "posture_deg": {
            d.name: math.degrees(q) for d, q in zip(body.dofs, problem.posture, strict=True)
        },
        "tasks": [task.model_dump() for task in spec.tasks],
        "fatigue": spec.fatigue.model_dump(),
        "simulation": spec.simulation.model_dump(),
        "solver": spec.solver.model_dump(),
        "parameters": [
            {
                "name": p.name,
                "value": p.value,
                "unit": p.unit,
                "status": p.status,
                "evidence": p.evidence,
                "source": p.source,
            }
            for p in problem.parameters
        ],
    }
