"""`make docs-figures`: every figure in docs/ is made again by a command."""

from __future__ import annotations

from pathlib import Path

import pytest

from casadi_posture.cli import main
from docs.generate.figures import COMMANDS, FIGURE_FOLDERS, Command, figures, make
from docs.generate.session import ROOT


def test_every_docs_figure_is_made_by_one_command() -> None:
    """The PNG files in docs/ are exactly the figures the commands make (a figure added by
    hand, or one a command no longer makes, fails here), each made by one command and
    shown on a page of docs/ or in the README."""
    shipped = {str(p.relative_to(ROOT)) for f in FIGURE_FOLDERS for p in (ROOT / f).glob("*.png")}
    made = [place for command in COMMANDS for place in command.figures.values()]
    assert sorted(made) == sorted(set(made)), "a figure made by two commands"
    assert set(made) == shipped
    pages = "".join(p.read_text() for p in [ROOT / "README.md", *(ROOT / "docs").glob("*.md")])
    for place in made:
        name = str(Path(place).relative_to("docs"))
        assert f"({name})" in pages or f"({place})" in pages, f"{place} is on no page"


@pytest.mark.parametrize("command", COMMANDS, ids=lambda c: c.line.split(" --")[0])
def test_each_command_is_one_the_tool_has(command: Command) -> None:
    """Each command's subcommand exists and its problem file (and recording) is shipped."""
    name, *args = command.args
    assert name in main.commands
    files = [a for a in args if a.startswith("problems/")]
    assert files and all((ROOT / f).is_file() for f in files), files


def test_a_figure_is_made_again_into_its_place(tmp_path: Path) -> None:
    """Fig. 3 drawn by its command lands at its place under the given folder, a PNG; a
    figure no command makes is refused, naming it."""
    made = make(["docs/frontal_elbow_fig3.png"], into=tmp_path, jobs=1)
    assert [command.line for command, _ in made] == [figures()["docs/frontal_elbow_fig3.png"].line]
    assert (tmp_path / "docs/frontal_elbow_fig3.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(KeyError, match=r"no command makes docs/nothing\.png"):
        make(["docs/nothing.png"], into=tmp_path)
