"""Parameter records with units, source and status, and the loader of the shipped data files.

A data file is TOML. A table holding a ``value`` key is one parameter; its
``unit`` is required. ``source``, ``status`` and ``evidence`` are inherited
from the nearest enclosing table that sets them, so a file states its source
once. ``status`` is ``verified`` (read in a primary text or two independent
transcriptions, or checked numerically) or ``estimate`` (our modelling
choice or a single unchecked transcription); ``evidence`` keeps a finer tag ([P],
[C1], [C2], [X], [E], [U]; ``docs/sources.md`` explains them).
Values the user overrides in a problem file get status ``user``.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, replace
from functools import cache
from importlib import resources
from typing import Any, Literal

Status = Literal["verified", "estimate", "user"]
_INHERITED = ("source", "status", "evidence")


@dataclass(frozen=True)
class Parameter:
    """One number (or list of numbers) the model uses, with where it comes from."""

    name: str
    value: Any
    unit: str
    source: str
    status: Status
    evidence: str = ""

    def overridden(self, value: Any, where: str) -> Parameter:
        """The same parameter with a user value from ``where`` (a file and key)."""
        return replace(self, value=value, source=where, status="user", evidence="")


@cache
def load(stem: str) -> dict[str, Parameter]:
    """The parameters of ``casadi_posture/data/<stem>.toml``, by dotted name."""
    text = resources.files("casadi_posture.data").joinpath(f"{stem}.toml").read_text("utf-8")
    table = tomllib.loads(text)
    out: dict[str, Parameter] = {}
    _collect(table, stem, {}, out)
    return out


def _collect(
    table: dict[str, Any], prefix: str, inherited: dict[str, str], out: dict[str, Parameter]
) -> None:
    context = {**inherited, **{k: table[k] for k in _INHERITED if k in table}}
    if "value" in table:
        missing = [k for k in ("unit", "source", "status") if k not in table and k not in context]
        if missing:
            raise ValueError(f"data parameter {prefix} lacks {', '.join(missing)}")
        if context["status"] not in ("verified", "estimate"):
            raise ValueError(f"data parameter {prefix} has status {context['status']!r}")
        out[prefix] = Parameter(
            name=prefix,
            value=table["value"],
            unit=table["unit"],
            source=context["source"],
            status=context["status"],
            evidence=context.get("evidence", ""),
        )
        return
    for key, item in table.items():
        if isinstance(item, dict):
            _collect(item, f"{prefix}.{key}", context, out)


#: The joint region whose data a region without its own takes.
DEFAULT_REGION = "general"


def regional(table: dict[str, Parameter], prefix: str, region: str, key: str) -> Parameter:
    """Parameter ``<prefix><region>.<key>`` of ``table``; a region without data takes the
    ``general`` one, under the region's name, its source saying so."""
    name = f"{prefix}{region}.{key}"
    if name in table:
        return table[name]
    general = table[f"{prefix}{DEFAULT_REGION}.{key}"]
    source = f"no fit for a region named {region!r}: the {DEFAULT_REGION} fit ({general.source})"
    return replace(general, name=name, source=source)


#: Name suffixes of the two sides of the body; a DOF or muscle group ``<name>_r`` or
#: ``<name>_l`` takes the shipped data of ``<name>``.
SIDES = ("_r", "_l")


def data_name(name: str) -> str:
    """The name under which the shipped data of a DOF or muscle group are filed: ``name``
    without its side suffix (``shoulder_flexion_r`` → ``shoulder_flexion``)."""
    for suffix in SIDES:
        if name.endswith(suffix):
            return name.removesuffix(suffix)
    return name


def value(stem: str, name: str) -> Any:
    """The value of parameter ``<stem>.<name>``."""
    return load(stem)[f"{stem}.{name}"].value
