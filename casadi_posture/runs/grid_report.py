"""report.html of a batch or what-if: every case's row in one sortable table, each case
linked to its own report.html, and a what-if's figures (its answers against the varied
keys) embedded; one self-contained page that opens offline."""

from __future__ import annotations

import base64
import html
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any
from urllib.parse import quote

from casadi_posture.runs.batch import CASES, BatchReport

#: The page's name in a batch or what-if folder.
PAGE = "report.html"


def _cell(value: Any) -> str:
    """A value as a table cell: numbers to 4 significant digits, empty for missing."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    if isinstance(value, float):
        return f"{value:.4g}"
    return html.escape(str(value))


def _case_link(out: Path, name: str) -> str:
    """The case's name, linked to its report.html when it has one."""
    page = out / CASES / name / PAGE
    label = html.escape(name)
    if not page.exists():
        return label
    return f'<a href="{quote(page.relative_to(out).as_posix())}">{label}</a>'


def grid_html(report: BatchReport, out: Path, heading: str, figures: Sequence[Path]) -> str:
    """The page: ``heading``, the counts by status, the rows of ``report`` (columns as in
    summary.csv) and ``figures`` (PNG files) embedded."""
    every = list(dict.fromkeys(k for row in report.rows for k in row))
    constant = [
        c for c in every if c != "case" and len({_cell(r.get(c)) for r in report.rows}) == 1
    ]
    columns = [c for c in every if c not in constant or len(report.rows) == 1]
    same = "".join(
        f"<li>{html.escape(c)}: {_cell(report.rows[0].get(c))}</li>"
        for c in constant
        if c not in columns and _cell(report.rows[0].get(c))
    )
    head = "".join(f"<th>{html.escape(c)}</th>" for c in columns)
    body = "".join(
        "<tr>"
        + "".join(
            f"<td>{_case_link(out, row['case']) if c == 'case' else _cell(row.get(c))}</td>"
            for c in columns
        )
        + "</tr>"
        for row in report.rows
    )
    counts = ", ".join(
        f"{len(report.with_status(s))} {s}" for s in ("ok", "flagged", "failed", "skipped")
    )
    images = "".join(
        f'<figure><img alt="{html.escape(p.stem)}" src="data:image/png;base64,'
        f'{base64.b64encode(p.read_bytes()).decode()}"><figcaption>{html.escape(p.name)}'
        "</figcaption></figure>"
        for p in figures
        if p.suffix == ".png" and p.exists()
    )
    stopped = " Interrupted: the finished cases only." if report.interrupted else ""
    return TEMPLATE.format(
        title=html.escape(heading),
        counts=html.escape(f"{len(report.rows)} cases: {counts}.{stopped}"),
        head=head,
        body=body,
        figures=images,
        same=f"<details><summary>The same for every case</summary><ul>{same}</ul></details>"
        if same
        else "",
    )


def write_grid_report(
    report: BatchReport, out: Path, heading: str, figures: Sequence[Path] = ()
) -> Path:
    """Write the page into ``out``/report.html (under a temporary name, then renamed)."""
    path = out / PAGE
    partial = path.with_suffix(".html.partial")
    partial.write_text(grid_html(report, out, heading, figures), encoding="utf-8")
    partial.replace(path)
    return path


TEMPLATE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{title}</title>
<style>
body {{ font-family: sans-serif; margin: 1.5em; color: #222; }}
h1 {{ font-size: 1.3em; }}
.table {{ overflow-x: auto; max-width: 100%; }}
table {{ border-collapse: collapse; font-size: 0.85em; }}
th, td {{ border: 1px solid #ccc; padding: 0.25em 0.5em; white-space: nowrap; }}
th {{ background: #f0f0f0; cursor: pointer; position: sticky; top: 0; }}
th.sorted-up::after {{ content: " ▲"; }}
th.sorted-down::after {{ content: " ▼"; }}
tr:nth-child(even) td {{ background: #fafafa; }}
figure {{ display: inline-block; margin: 1em 1em 0 0; }}
img {{ max-width: 640px; border: 1px solid #ddd; }}
</style></head><body>
<h1>{title}</h1>
<p>{counts} Click a column's heading to sort by it; a case's name opens its own report.</p>
{same}
<div class="table"><table id="grid"><thead><tr>{head}</tr></thead>
<tbody>{body}</tbody></table></div>
{figures}
<script>
document.querySelectorAll("#grid th").forEach((th, column) => {{
  th.addEventListener("click", () => {{
    const tbody = document.querySelector("#grid tbody");
    const rows = Array.from(tbody.rows);
    const up = !th.classList.contains("sorted-up");
    const key = (row) => {{
      const text = row.cells[column].textContent.trim();
      const number = Number(text);
      return text !== "" && !Number.isNaN(number) ? [0, number] : [1, text];
    }};
    rows.sort((a, b) => {{
      const [p, q] = [key(a), key(b)];
      const order = p[0] - q[0] || (p[1] < q[1] ? -1 : p[1] > q[1] ? 1 : 0);
      return up ? order : -order;
    }});
    rows.forEach((row) => tbody.appendChild(row));
    const heads = document.querySelectorAll("#grid th");
    heads.forEach((h) => h.classList.remove("sorted-up", "sorted-down"));
    th.classList.add(up ? "sorted-up" : "sorted-down");
  }});
}});
</script>
</body></html>
"""
