"""The package's layers: every import runs downward (or within one group), so the tree reads
bottom-up like the data's path: problem-file specs, the body (the built-in models are trees
a file could hold), biomechanics, IK (whose comfort level counts torques and strength), the
resolved problem, the fatigue-driven adjustment, the simulation, output, runs, the CLI."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "casadi_posture"

#: Floor of each group (a subpackage or a top-level module), from the ground up.
FLOORS = {
    "errors": 0,
    "interrupt": 0,
    "frames": 0,
    "compiled": 0,
    "data": 1,
    "spec": 2,
    "body": 3,
    "biomech": 4,
    "ik": 5,
    "problem": 6,
    "ergonomics": 6,
    "motion": 6,
    "people": 6,
    "static": 7,
    "adjustment": 7,
    "simulation": 8,
    "description": 8,
    "sensitivity_analysis": 8,
    "workplace_design": 8,
    "output": 9,
    "runs": 10,
    "api": 11,
    "cli": 12,
    "console": 13,
    "__init__": 14,
    "__main__": 14,
}


def _group(module: str) -> str:
    return module.removeprefix("casadi_posture.").split(".")[0]


def _imports(path: Path) -> set[str]:
    """The casadi_posture modules a file imports (at top level or inside functions)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module:
            if node.level:
                raise AssertionError(f"{path}: relative import of {node.module}")
            if node.module.startswith("casadi_posture."):
                found.add(node.module)
            elif node.module == "casadi_posture":
                found |= {f"casadi_posture.{a.name}" for a in node.names}
        elif isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.startswith("casadi_posture.")}
    return found


def test_every_import_runs_downward() -> None:
    wrong = []
    for path in sorted(PACKAGE.rglob("*.py")):
        here = _group(".".join(path.relative_to(PACKAGE).with_suffix("").parts))
        for target in _imports(path):
            there = _group(target)
            if there == "__version__":
                continue
            if FLOORS[there] > FLOORS[here] or (FLOORS[there] == FLOORS[here] and there != here):
                wrong.append(f"{path.relative_to(PACKAGE)} imports {target}")
    assert not wrong, "\n".join(wrong)


def test_every_module_has_a_floor() -> None:
    groups = {
        _group(".".join(p.relative_to(PACKAGE).with_suffix("").parts))
        for p in PACKAGE.rglob("*.py")
    }
    assert groups <= set(FLOORS)
