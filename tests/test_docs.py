"""The repository's documents: self-contained, and true to what the tool writes."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_no_file_refers_to_the_internal_notes() -> None:
    """A clone has no `shared/` folder: nothing may send a reader there or to its spec."""
    pattern = re.compile(r"shared/|\bSPEC\b|biomech-data|ik-solvers|body-3d-data")
    offenders = []
    for path in ROOT.rglob("*"):
        parts = set(path.relative_to(ROOT).parts)
        if parts & {".git", ".venv", "out", "__pycache__", ".pytest_cache"} or not path.is_file():
            continue
        if path.suffix not in {".py", ".toml", ".md", ".cff", ".txt", ""} or "egg-info" in str(
            path
        ):
            continue
        if path.name == "test_docs.py":
            continue
        for number, line in enumerate(path.read_text(errors="ignore").splitlines(), 1):
            if pattern.search(line):
                offenders.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()[:80]}")
    assert not offenders, "\n".join(offenders)


def _table(heading: str, column: int = 0) -> list[str]:
    """The backticked names in ``column`` of the first table after ``heading`` in
    docs/outputs.md (several per cell, comma-separated)."""
    text = (ROOT / "docs" / "outputs.md").read_text()
    lines = text[text.index(heading) :].splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("|"))
    names = []
    for line in lines[start + 2 :]:
        if not line.startswith("|"):
            break
        names += re.findall(r"`([^`]+)`", line.split("|")[column + 1])
    return names


def _pattern(documented: str) -> re.Pattern[str]:
    """A documented column name as a regex: ``<dof>`` stands for any name; a name starting
    with ``_`` continues the previous one (``<effector>_x_m``, ``_y_m``)."""
    return re.compile(
        "^"
        + re.sub(
            r"<[a-z]+>", "[a-z0-9_]+", re.escape(documented).replace(r"\<", "<").replace(r"\>", ">")
        )
        + "$"
    )


def _documented_columns(heading: str) -> list[re.Pattern[str]]:
    names, patterns = _table(heading), []
    for name in names:
        if name.startswith("_") and patterns:
            stem = patterns[-1].pattern.removeprefix("^").removesuffix("$")
            stem = stem[: stem.rfind("_", 0, stem.rfind("_"))]
            patterns.append(re.compile(f"^{stem}{re.escape(name)}$"))
        else:
            patterns.append(_pattern(name))
    return patterns


def _undocumented(columns: list[str], patterns: list[re.Pattern[str]]) -> list[str]:
    return [c for c in columns if not any(p.match(c) for p in patterns)]


def _unused(columns: list[str], patterns: list[re.Pattern[str]]) -> list[str]:
    return [p.pattern for p in patterns if not any(p.match(c) for c in columns)]


def test_timeline_columns_and_event_kinds_are_documented(tmp_path: Path) -> None:
    from typing import get_args

    import casadi_posture as cp
    from casadi_posture.adjustment.constraint import EventKind

    header: list[str] = []
    for name in ("line_plane_hysteresis", "standing_wall_horizontal"):  # an arm, a standing body
        run = cp.simulate(
            cp.load(ROOT / "problems" / f"{name}.toml", {"simulation.duration_s": 5.0})
        )
        run.write(tmp_path / name, figures=False)
        header += (tmp_path / name / "timeline.csv").read_text().splitlines()[0].split(",")
    patterns = _documented_columns("### `timeline.csv`")
    assert _undocumented(header, patterns) == []
    assert _unused(header, patterns) == []
    assert set(_table("### `events.csv`")) == set(get_args(EventKind))
    summary = (tmp_path / "standing_wall_horizontal" / "summary.json").read_text()
    documented = {name for cell in _table("### `summary.json`") for name in cell.split(".")}
    import json

    assert set(json.loads(summary)) <= documented


def test_batch_summary_columns_are_documented(tmp_path: Path) -> None:
    import casadi_posture as cp

    report = cp.whatif(
        ROOT / "problems" / "holding_m45.toml",
        {"loads[0].mass_kg": [2.0]},
        tmp_path / "w",
        overrides={"simulation.duration_s": 200.0},
    )
    header = (tmp_path / "w" / "summary.csv").read_text().splitlines()[0].split(",")
    varied = [c for c in header if c not in ("loads[0].mass_kg", "simulation.duration_s")]
    patterns = _documented_columns("Columns of `summary.csv`")
    assert report.rows[0]["status"] == "ok"
    assert _undocumented(varied, patterns) == []
    assert (tmp_path / "w" / "whatif.csv").read_text() == (
        tmp_path / "w" / "summary.csv"
    ).read_text()
    assert sorted(p.name for p in report.figures) == sorted(
        p.name for p in (tmp_path / "w").glob("*.png")
    )


def _python_examples(name: str) -> list[tuple[str, str]]:
    """Each ```python block of a document that a ```text block (its output) follows."""
    text = (ROOT / name).read_text()
    pattern = r"```python\n(.*?)```\n\n```text\n(.*?)```"
    return re.findall(pattern, text, flags=re.DOTALL)


@pytest.mark.parametrize("document", ["docs/api.md", "README.md"])
def test_python_examples_print_what_the_documents_show(document: str, tmp_path: Path) -> None:
    examples = _python_examples(document)
    assert examples, f"{document} shows no Python example with its output"
    shutil.copytree(ROOT / "problems", tmp_path / "problems")
    for code, shown in examples:
        (tmp_path / "example.py").write_text(code)
        ran = subprocess.run(
            [sys.executable, "example.py"], cwd=tmp_path, capture_output=True, text=True
        )
        assert ran.returncode == 0, ran.stderr
        assert ran.stdout.rstrip() == shown.rstrip()


def _shell_commands() -> list[str]:
    """Every runnable casadi-posture command the documents and the --help examples show:
    console lines, inline code and help epilogs; synopses with placeholders (PROBLEM,
    KEY=VALUE, [--json]) are not commands."""
    from click.testing import CliRunner

    from casadi_posture.cli import main

    pages = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    # a generated region's template (its opening comment) is not shown: its rendering is
    texts = [re.sub(r"<!-- generated by .*?-->", "", p.read_text(), flags=re.DOTALL) for p in pages]
    texts += [
        CliRunner().invoke(main, [name, "--help"]).output.replace("\\\n", " ")
        for name in main.commands
    ]
    found = []
    for text in texts:
        found += re.findall(r"^\$ (casadi-posture [^\n]+)", text, flags=re.MULTILINE)
        found += [" ".join(c.split()) for c in re.findall(r"`(casadi-posture [^`]+)`", text)]
        found += re.findall(r"^ +(casadi-posture [^\n]+)", text, flags=re.MULTILINE)
    return sorted({c for c in found if not re.search(r"\b[A-Z]{3,}\b|\.\.\.", c)})


def test_shell_examples_survive_failglob_and_zsh(tmp_path: Path) -> None:
    """Copied into bash with failglob or into zsh, no example fails on an unquoted pattern
    (``--vary loads[0].mass_kg=1`` matches no file: "no matches found")."""
    shutil.copytree(ROOT / "problems", tmp_path / "problems")
    shells = [["bash", "-O", "failglob", "-c"]]
    if shutil.which("zsh"):
        shells.append(["zsh", "-c"])
    commands = _shell_commands()
    assert len(commands) > 10
    for shell in shells:
        for command in commands:
            ran = subprocess.run(
                [*shell, f"printf '%s\\n' {command}"], cwd=tmp_path, capture_output=True
            )
            assert ran.returncode == 0, f"{shell[0]}: {command}: {ran.stderr.decode()}"
