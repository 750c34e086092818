"""Every ``$ casadi-posture ...`` console example in the README and docs/ prints what the
document shows."""

from __future__ import annotations

import shlex
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from casadi_posture.cli import main

ROOT = Path(__file__).resolve().parents[1]


DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _examples() -> list[tuple[str, str]]:
    examples = []
    for document in DOCUMENTS:
        examples += _console_examples(document.read_text())
    return examples


def _console_examples(text: str) -> list[tuple[str, str]]:
    """Each command of a ```console block and the lines it prints."""
    examples, command, lines, in_block = [], None, [], False
    for line in text.splitlines():
        if line.startswith("```console"):
            in_block = True
            continue
        if in_block and (line.startswith("```") or line.startswith("$ ")):
            if command is not None:
                examples.append((command, "\n".join(lines)))
            command, lines = None, []
            if line.startswith("```"):
                in_block = False
                continue
        if in_block and line.startswith("$ casadi-posture "):
            command = line.removeprefix("$ casadi-posture ")
        elif in_block and command is not None:
            lines.append(line)
    return examples


@pytest.mark.parametrize(("command", "shown"), _examples(), ids=lambda v: v[:40])
def test_readme_example_runs_as_shown(
    command: str, shown: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    shutil.copytree(ROOT / "problems", tmp_path / "problems")
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(main, shlex.split(command))
    assert result.output.rstrip() == shown.rstrip()


def test_readme_has_examples() -> None:
    assert len(_examples()) >= 3


def test_readme_names_every_shipped_model() -> None:
    """No stale status: the README names each body model the package ships, and the
    templates `init` offers."""
    from casadi_posture.body.models import MODELS
    from casadi_posture.data.templates import TEMPLATES

    text = (ROOT / "README.md").read_text()
    for name in MODELS:
        assert f"`{name}`" in text, name
    for name in ("shelf", "seated", "tree"):
        assert name in TEMPLATES and f"init {name}" in text, name
