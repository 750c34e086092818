"""report.html of a batch or what-if: every case's row in one sortable table, each case
linked to its own report.html, and a what-if's figures (its answers against the varied
keys) embedded; one self-contained page that opens offline."""

from __future__ import annotations

import base64
import html
from collections.abc import Sequence
from pathlib import Path
from urllib.parse import quote

from casadi_posture.output.html_page import cell, scripts, write_page
from casadi_posture.runs.batch import CASES, BatchReport

#: The page's name in a batch or what-if folder.
PAGE = "report.html"


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
    constant = [c for c in every if c != "case" and len({cell(r.get(c)) for r in report.rows}) == 1]
    columns = [c for c in every if c not in constant or len(report.rows) == 1]
    same = "".join(
        f"<li>{html.escape(c)}: {cell(report.rows[0].get(c))}</li>"
        for c in constant
        if c not in columns and cell(report.rows[0].get(c))
    )
    head = "".join(f"<th>{html.escape(c)}</th>" for c in columns)
    body = "".join(
        "<tr>"
        + "".join(
            f"<td>{_case_link(out, row['case']) if c == 'case' else cell(row.get(c))}</td>"
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
        script=scripts("sortable.js"),
    )


def write_grid_report(
    report: BatchReport, out: Path, heading: str, figures: Sequence[Path] = ()
) -> Path:
    """Write the page into ``out``/report.html (under a temporary name, then renamed)."""
    return write_page(grid_html(report, out, heading, figures), out / PAGE)


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
{script}
sortable(document.getElementById("grid"));
</script>
</body></html>
"""
