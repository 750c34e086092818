"""Console blocks: each ``$ casadi-posture ...`` command of the block is run in the
document's working folder and the block rewritten with what it prints.

Arguments of the marker: ``keep=REGEX`` keeps only the printed lines that match (from their
start; each run of dropped lines becomes one ``...``), ``cut=REGEX`` shortens a kept line
whose start it matches to that match followed by `` ...``, ``columns='A;B;...'`` keeps
only the named columns of a printed table (its header above a line of dashes; each run of
dropped columns becomes one ``...`` column).
"""

from __future__ import annotations

import glob
import itertools
import re
import shlex

from click.testing import CliRunner

from .regions import Region
from .session import Session

#: Wall-clock figures in what the commands print: compared as equal whatever their value.
TIMINGS = re.compile(
    r"\d+(?:\.\d+)? ms\b|\d+(?:\.\d+)? s wall|\d+ % in IK|(?<=iterations, )\d+(?:\.\d+)? s\b"
)

ELIDED = "..."


def commands(body: str) -> tuple[str, list[list[str]]]:
    """The fence's opening line and each command as its lines (a line ending with ``\\``
    continues on the next)."""
    lines = body.rstrip("\n").splitlines()
    if not lines or not lines[0].startswith("```") or lines[-1] != "```":
        raise ValueError("a console region holds one fenced block")
    found: list[list[str]] = []
    continued = False
    for line in lines[1:-1]:
        if continued:
            found[-1].append(line)
        elif line.startswith("$ "):
            if not line.startswith("$ casadi-posture "):
                raise ValueError(f"only casadi-posture commands are run: {line!r}")
            found.append([line])
        continued = line.endswith("\\") and bool(found)
    if not found:
        raise ValueError("a console region holds no $ casadi-posture command")
    return lines[0], found


def expanded(word: str) -> list[str]:
    """``word`` as the shell passes it: a word with ``*`` becomes the files it matches in
    the current folder, sorted (itself when none does)."""
    return (sorted(glob.glob(word)) or [word]) if "*" in word else [word]


def run(command: list[str], session: Session) -> str:
    """What ``command`` (its lines as written) prints, run in the session's folder."""
    from casadi_posture.cli import main

    words = shlex.split(" ".join(line.removesuffix("\\") for line in command))
    with session.inside():
        words = [found for word in words for found in expanded(word)]
        result = CliRunner().invoke(main, words[2:], prog_name="casadi-posture")
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise RuntimeError(f"{command[0]} raised {result.exception!r}") from result.exception
    return result.output.rstrip("\n")


def shorten(output: str, keep: str | None, cut: str | None) -> list[str]:
    """The printed lines as the block shows them: those matching ``keep``, each cut after
    what ``cut`` matches of it."""
    shown: list[str] = []
    for line in output.splitlines():
        if keep is not None and not re.match(keep, line):
            if not shown or shown[-1] != ELIDED:
                shown.append(ELIDED)
            continue
        short = re.match(cut, line) if cut is not None else None
        shown.append(f"{short[0]} {ELIDED}" if short and short.end() < len(line) else line)
    return shown


def in_table(line: str, spans: list[tuple[int, int]]) -> bool:
    """Whether ``line`` is a row of the table whose columns span ``spans``: not blank, and
    blank between the columns."""
    gaps = [(a[1], b[0]) for a, b in itertools.pairwise(spans)]
    return bool(line.strip()) and all(not line[start:end].strip() for start, end in gaps)


def table_columns(lines: list[str], names: list[str]) -> list[str]:
    """``lines`` with every table among them cut to the columns whose header is in
    ``names``."""
    out, spans = [], None
    for i, line in enumerate(lines):
        below = lines[i + 1] if i + 1 < len(lines) else ""
        if re.fullmatch(r"-+( +-+)*", below):
            spans = [m.span() for m in re.finditer(r"-+", below)]
            kept = [span for span in spans if line[span[0] : span[1]].strip() in names]
            if len(kept) != len(names):
                raise ValueError(f"columns {names} not all in the table headed {line!r}")
        elif spans is not None and not in_table(line, spans):
            spans = None
        if spans is None:
            out.append(line)
            continue
        cells, previous = [], 0
        for start, end in spans:
            if (start, end) in kept:
                if spans.index((start, end)) != previous:
                    cells.append(ELIDED)
                cells.append(line[start:end].ljust(end - start))
                previous = spans.index((start, end)) + 1
        if previous != len(spans):
            cells.append(ELIDED)
        out.append("  ".join(cells).rstrip())
    return out


def generate(region: Region, session: Session) -> str:
    """The console block with every command's output as it is printed today."""
    fence, found = commands(region.body)
    keep, cut = region.args.get("keep"), region.args.get("cut")
    lines = [fence]
    for command in found:
        lines += command
        printed = run(command, session).splitlines()
        if "columns" in region.args:
            printed = table_columns(printed, region.args["columns"].split(";"))
        lines += shorten("\n".join(printed), keep, cut)
    return "\n".join([*lines, "```"])
