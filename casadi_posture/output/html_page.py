"""What every HTML page of ours shares: plotly.js embedded once, gzip-compressed (the browser
inflates it, so a page opens offline), JSON safe inside a script element, the scripts,
tables, and a page written whole or not at all."""

from __future__ import annotations

import base64
import gzip
import html
import json
import math
import os
from collections.abc import Sequence
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

from casadi_posture.output.plotly_json import plotly_js, version
from casadi_posture.problem import Problem
from casadi_posture.spec.overrides import changes


@cache
def plotly_gzip() -> str:
    """plotly.js, gzip-compressed and base64-encoded (about 1.9 MB instead of 4.8). Kept
    in the user's cache folder per plotly version (compressing takes 0.2 s); made again
    when that copy is missing or cannot be written."""
    cached = _cache_folder() / f"plotly-{version()}.min.js.gz.b64"
    try:
        return cached.read_text(encoding="ascii")
    except OSError:
        pass
    text = base64.b64encode(gzip.compress(plotly_js().encode(), 9, mtime=0)).decode()
    try:
        cached.parent.mkdir(parents=True, exist_ok=True)
        partial = cached.with_name(f"{cached.name}.{os.getpid()}.partial")
        partial.write_text(text, encoding="ascii")
        partial.replace(cached)  # whole or not at all, if two runs write it at once
    except OSError:
        pass
    return text


def _cache_folder() -> Path:
    """casadi_posture's folder in the user's cache (XDG_CACHE_HOME, else ~/.cache)."""
    root = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(root) / "casadi_posture"


def script_json(value: Any) -> str:
    """``value`` as compact JSON, safe inside a <script> element (no NaN: missing is null)."""
    text = json.dumps(value, separators=(",", ":"), allow_nan=False)
    return text.replace("</", "<\\/")


def scripts(*names: str) -> str:
    """The package's page scripts ``names``, in order (``viewer.js``: the body's view;
    ``sortable.js``: tables sorted by a click on a heading)."""
    folder = resources.files("casadi_posture.output")
    return "\n".join(folder.joinpath(name).read_text() for name in names)


def cell(value: Any) -> str:
    """A value as a table cell: numbers to 4 significant digits, empty for missing."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    if isinstance(value, float):
        return f"{value:.4g}"
    return html.escape(str(value))


def table(headers: Sequence[str], rows: Sequence[Sequence[Any]], **attributes: str) -> str:
    """An HTML table of ``rows`` (cells by ``cell``) under ``headers``."""
    extra = "".join(f' {k.rstrip("_")}="{html.escape(v)}"' for k, v in attributes.items())
    head = "".join(f"<th>{html.escape(h)}</th>" for h in headers)
    body = "".join("<tr>" + "".join(f"<td>{cell(v)}</td>" for v in row) + "</tr>" for row in rows)
    return f"<table{extra}><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def write_page(text: str, path: Path) -> Path:
    """``text`` into ``path``, written whole or not at all (a Ctrl-C leaves no half page)."""
    partial = path.with_name(path.name + ".partial")
    try:
        partial.write_text(text, encoding="utf-8")
        partial.replace(path)
    finally:
        partial.unlink(missing_ok=True)
    return path


def problem_line(problem: Problem) -> str:
    """The problem file and the keys set on the command line, for a page's subtitle."""
    sets = changes(problem.overrides)
    return f"{problem.path} with {sets}" if sets else str(problem.path)


#: The head of every page with a body's view (a ``str.format`` template: ``{title}``; the
#: page's own style follows, then ``</style>``).
HEAD = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}</title>
<style>
body {{ font-family: system-ui, sans-serif; margin: 0 1em 2em; color: #222; }}
h1 {{ font-size: 1.3em; margin: 0.5em 0 0; }} .sub {{ color: #666; font-size: 0.85em; }}
ul {{ margin: 0.3em 0; padding-left: 1.2em; }} .flags {{ color: #b00020; }}
.ok {{ color: #2a7a2a; margin: 0.2em 0; }} #loading {{ color: #666; }}
#views {{ display: flex; flex-wrap: wrap; gap: 0.5em; }}
"""
