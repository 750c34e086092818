"""A solved posture as ``solve --json`` prints it and solve.json holds it: the solver's
status, the levels' residuals, the posture [deg], the torques [N·m] and loads [%MVC], the
share of people capable, the plausibility, RULA/REBA and the low back."""

from __future__ import annotations

from typing import Any

from casadi_posture.ik.result import ACHIEVED_TOLERANCE
from casadi_posture.output import low_back
from casadi_posture.output.scores import static_report
from casadi_posture.static import StaticAnswer


def answer_json(answer: StaticAnswer, problem: str) -> dict[str, Any]:
    """``answer`` (solved by the IK) of the problem file ``problem``, as a JSON object."""
    result = answer.ik
    assert result is not None, "a solved answer"
    return {
        "problem": problem,
        "solver": result.solver,
        "status": result.status,
        "success": result.success,
        "reached": answer.reached,
        "flags": list(answer.flags),
        "notes": list(answer.problem.notes),
        "iterations": result.iterations,
        "wall_time_s": result.wall_time_s,
        "posture_deg": answer.posture_deg,
        "achieved_tolerance": ACHIEVED_TOLERANCE,
        "levels": [level.__dict__ for level in answer.levels],
        "at_limits": list(result.at_limits),
        "inequality_active": result.inequality_active,
        "endurance_rule": answer.rule,
        "torques": {"dofs": answer.dofs(), "half_joints": answer.half_joints()},
        "capable": answer.capable_report(),
        "plausibility": answer.plausibility.to_dict() if answer.plausibility else None,
        "rula_reba": static_report(answer.problem, answer.scores),
        "low_back": low_back.static_report(answer.low_back),
    }
