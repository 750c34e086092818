"""Plotly figures as the plain JSON data plotly.js reads, built without plotly's Python
objects (which validate and copy every number: half a second of a 20-minute run's page):
numbers rounded for a page, rows stacked on one shared time axis, a horizontal line across
a row, plotly's own templates and plotly.js itself, read from the installed plotly
package without importing it."""

from __future__ import annotations

import json
from collections.abc import Sequence
from functools import cache
from importlib import metadata, util
from pathlib import Path
from typing import Any

import numpy as np

#: Significant digits of the numbers in a page.
DIGITS = 4


def rounded(values: Any, digits: int = DIGITS) -> Any:
    """Numbers (nested lists or arrays) to ``digits`` significant digits, as nested lists of
    floats that print short (the nearest double to the rounded decimal); NaN and ±inf as
    None."""
    array = np.asarray(values, dtype=float)
    finite = np.isfinite(array)
    magnitude = np.abs(np.where(finite & (array != 0.0), array, 1.0))
    shift = digits - 1 - np.floor(np.log10(magnitude))
    up, down = 10.0 ** np.maximum(shift, 0.0), 10.0 ** np.maximum(-shift, 0.0)
    with np.errstate(invalid="ignore"):
        near = np.round(array * up / down) * down / up
    if finite.all():
        return near.tolist()
    return np.where(finite, near, None).tolist()


def stacked_rows(
    titles: Sequence[str], heights: Sequence[float], spacing: float
) -> tuple[dict[str, Any], list[tuple[float, float]]]:
    """The layout of rows stacked top to bottom that share the bottom row's x axis (its tick
    labels only shown), ``heights`` relative and ``spacing`` a share of the figure's
    height between rows, each titled above its left corner; and each row's vertical
    domain (0 bottom, 1 top). Row ``r`` (from 1) plots on axes ``x{r}``/``y{r}`` (``x``/``y``
    for the first)."""
    n = len(titles)
    unit = (1.0 - spacing * (n - 1)) / float(sum(heights))
    layout: dict[str, Any] = {"annotations": []}
    domains, top = [], 1.0
    for r, (text, height) in enumerate(zip(titles, heights, strict=True), start=1):
        bottom = max(top - unit * height, 0.0)
        domains.append((bottom, top))
        x, y = axis_name("x", r), axis_name("y", r)
        layout[f"xaxis{r if r > 1 else ''}"] = {"anchor": y, "domain": [0.0, 1.0]} | (
            {"matches": axis_name("x", n), "showticklabels": False} if r < n else {}
        )
        layout[f"yaxis{r if r > 1 else ''}"] = {"anchor": x, "domain": [bottom, top]}
        layout["annotations"].append(
            {"text": text, "x": 0, "xanchor": "left", "xref": "paper", "y": top,
             "yanchor": "bottom", "yref": "paper", "showarrow": False, "font": {"size": 12}}
        )  # fmt: skip
        top = bottom - spacing
    return layout, domains


def axis_name(axis: str, row: int) -> str:
    """A row's axis as a trace names it: ``x``, ``x2``, ..."""
    return f"{axis}{row if row > 1 else ''}"


def hline(y: float, row: int, line: dict[str, Any]) -> dict[str, Any]:
    """A horizontal line across a row (a layout shape) at ``y`` in the row's units."""
    return {
        "type": "line", "line": line, "x0": 0, "x1": 1, "xref": f"{axis_name('x', row)} domain",
        "y0": y, "y1": y, "yref": axis_name("y", row),
    }  # fmt: skip


def _plotly_file(*parts: str) -> Path:
    """A file of the installed plotly package (found, not imported)."""
    spec = util.find_spec("plotly")
    if spec is None or not spec.submodule_search_locations:
        raise ModuleNotFoundError("plotly is not installed")
    return Path(spec.submodule_search_locations[0], *parts)


@cache
def template(name: str) -> dict[str, Any]:
    """One of plotly's templates (``plotly``, ``plotly_white``, ...) as plotly.js reads it in
    a layout's ``template``."""
    text = _plotly_file("package_data", "templates", f"{name}.json").read_text(encoding="utf-8")
    return json.loads(text)


@cache
def plotly_js() -> str:
    """plotly.js, minified, as the installed plotly package ships it."""
    return _plotly_file("package_data", "plotly.min.js").read_text(encoding="utf-8")


@cache
def version() -> str:
    """The installed plotly package's version."""
    return metadata.version("plotly")
