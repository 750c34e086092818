"""casadi_posture: how a posture changes as muscles tire (Rodriguez & Boulic 2008) on CasADi.

    >>> import casadi_posture as cp
    >>> problem = cp.load("problems/holding_m45.toml")
    >>> run = cp.simulate(problem)
    >>> run.summary()["exhausted_group"]["half_joint"]
    'elbow_flexors'

The names below are the public API (``docs/api.md``); they load on first use, so that
``import casadi_posture`` stays quick.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

#: Public name -> the module that defines it.
_PUBLIC = {
    "load": "casadi_posture.api",
    "loads": "casadi_posture.api",
    "from_dict": "casadi_posture.api",
    "describe": "casadi_posture.api",
    "torques": "casadi_posture.api",
    "curve": "casadi_posture.api",
    "plot_curve": "casadi_posture.api",
    "solve": "casadi_posture.api",
    "write_solve": "casadi_posture.api",
    "simulate": "casadi_posture.api",
    "evaluate": "casadi_posture.api",
    "read_motion": "casadi_posture.api",
    "Recording": "casadi_posture.motion.recording",
    "compare": "casadi_posture.api",
    "write_compare": "casadi_posture.api",
    "whatif": "casadi_posture.api",
    "batch": "casadi_posture.api",
    "population": "casadi_posture.api",
    "PopulationReport": "casadi_posture.runs.population",
    "Simulation": "casadi_posture.api",
    "sensitivity": "casadi_posture.sensitivity_analysis.analysis",
    "Sensitivity": "casadi_posture.sensitivity_analysis.analysis",
    "design": "casadi_posture.workplace_design",
    "Design": "casadi_posture.workplace_design",
    "duty_cycle": "casadi_posture.runs.duty_cycle",
    "DutyCycle": "casadi_posture.runs.duty_cycle",
    "Problem": "casadi_posture.problem",
    "StaticAnswer": "casadi_posture.static",
    "GroupLoad": "casadi_posture.static",
    "Level": "casadi_posture.static",
    "TorqueCurve": "casadi_posture.biomech.curve",
    "Comparison": "casadi_posture.runs.compare",
    "BatchReport": "casadi_posture.runs.batch",
    "CasadiPostureError": "casadi_posture.errors",
    "ProblemError": "casadi_posture.errors",
}

__all__ = ["__version__", *_PUBLIC]


def _version() -> str:
    """The installed version; looked up on first use (``importlib.metadata`` is slow to
    import, and the command line must answer Ctrl-C from its first milliseconds)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("casadi_posture")
    except PackageNotFoundError:  # running from a source tree that is not installed
        return "0+unknown"


def __getattr__(name: str) -> Any:
    if name == "__version__":
        value = globals()["__version__"] = _version()
        return value
    if name in _PUBLIC:
        value = getattr(import_module(_PUBLIC[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'casadi_posture' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
