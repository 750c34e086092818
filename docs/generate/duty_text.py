"""docs/workflows.md: the prose around ``duty-cycle``, the sustainable duty cycles and
Potvin's guideline beside them, as ``casadi_posture.runs.duty_cycle`` finds them:
``duty-cycle problem=PATH NAME='S,S,... [KEY=VALUE ...] [precision=P]' ...`` searches the
shipped problem for each rest time S [s] of each NAME, with the file's KEYs set and
``--precision P``; the template reads ``{NAME[rest][S][duty_cycle_pct]}``. The searches
run in parallel."""

from __future__ import annotations

from typing import Any

import casadi_posture as cp
from casadi_posture.runs.duty_cycle import DEFAULT_PRECISION, DutyCycle, duty_cycle

from . import parallel, runs
from .regions import Region
from .session import ROOT, Session


def search(path: str, keys: str, t_off_s: float, precision: float) -> dict[str, Any]:
    """The duty-cycle search of the problem at ``path`` (with ``keys``, as ``set=``) for a
    rest of ``t_off_s`` [s]: its ``duty_cycle_pct`` and ``bracket_pct`` [%], the holds
    ``sustainable_s`` and ``failing_s`` [s], ``apart``: how far apart they are, in words
    ('one time step apart, which the output says limits it'), ``first_s``, when the first
    trial (the hold without rest) reaches the threshold [s], and its ``group``; ``effort``
    the hold's effort [%MVC], ``potvin_pct`` the duty cycle Potvin's guideline accepts for
    it [%] and ``potvin_effort`` the effort it accepts at ours [%MVC]; ``mass_kg`` each
    load's mass [kg]."""
    problem = cp.load(ROOT / path, runs.overrides(keys))
    found = duty_cycle(problem, t_off_s, precision=precision)
    first, guide = found.trials[0], found.guideline() or {}
    return {
        "duty_cycle_pct": found.duty_cycle_pct,
        "bracket_pct": found.duty_cycle_bracket_pct,
        "sustainable_s": found.sustainable_t_on_s,
        "failing_s": found.failing_t_on_s,
        "apart": apart(found),
        "first_s": first.threshold_s,
        "group": (first.half_joint or "").replace("_", " "),
        "effort": guide.get("effort_pct_mvc"),
        "potvin_pct": guide.get("acceptable_duty_cycle_pct"),
        "potvin_effort": guide.get("acceptable_effort_at_duty_cycle_pct_mvc"),
        "mass_kg": [load.mass for load in problem.loads],
    }


def apart(found: DutyCycle) -> str:
    """How far apart the bracket's holds are, and whether the time step limits it."""
    if found.step_limited:
        return "one time step apart, which the output says limits it"
    if found.sustainable_t_on_s is None or found.failing_t_on_s is None:
        return "not bracketed"
    return f"{found.failing_t_on_s - found.sustainable_t_on_s:g} s apart"


def percent(value: float) -> str:
    """A duty cycle to 0.1 %, a whole one without its decimal: 77.94 → '77.9', 0 → '0'."""
    return f"{value:.1f}".removesuffix(".0")


def values(region: Region, session: Session) -> dict[str, Any]:
    """For each ``NAME=``: ``rest[S]``, :func:`search` for each of its rest times S [s,
    whole], and ``listed``, their duty cycles [%] as text ('0, 77.9 and 74.6')."""
    args = dict(region.args)
    path, cases = args.pop("problem"), {}
    for name, text in args.items():
        rests, *words = text.split()
        keys = dict(word.split("=", 1) for word in words)
        precision = float(keys.pop("precision", DEFAULT_PRECISION))
        keyed = ";".join(f"{k}={v}" for k, v in keys.items())
        cases[name] = {int(t): (path, keyed, float(t), precision) for t in rests.split(",")}
    found = parallel.compute(search, [c for named in cases.values() for c in named.values()])
    named: dict[str, Any] = {}
    for name, by_rest in cases.items():
        facts = {t: found[case] for t, case in by_rest.items()}
        listed = runs.listed([percent(f["duty_cycle_pct"]) for f in facts.values()])
        named[name] = {"rest": facts, "listed": listed}
    return named
