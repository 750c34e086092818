"""Every figure of docs/ made again by the command that makes it: ``make docs-figures``
(``python -m docs.generate.figures [DOCS/FIGURE.png ...]``).

Each command of :data:`COMMANDS` runs, as a reader would run it, in a fresh folder holding
a copy of ``problems/``, and the figures it writes are copied over their places in docs/
(the commands run side by side, ``--jobs`` at a time). The figures are not compared with
the files in docs/ byte for byte -- matplotlib's output differs between its versions -- but
``tests/test_docs_figures.py`` checks that every PNG in docs/ is made by one command here,
so a figure no command makes again cannot be added. The numbers printed around a figure
are the generated regions' (``make docs-check``).
"""

from __future__ import annotations

import argparse
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from .session import ROOT

#: The folders of docs/ whose PNG files are figures (``tests/test_docs_figures.py``).
FIGURE_FOLDERS = ("docs", "docs/gallery", "docs/scenarios")

#: Exit codes of a command that drew its figures: 0, and 1 for an answer it flags.
DREW = (0, 1)


@dataclass(frozen=True, eq=False)
class Command:
    """A ``casadi-posture`` command line as the docs show it (its own ``--out`` included)
    and the figures it writes: {file it writes, relative to its working folder: the
    figure's place in the repository}."""

    line: str
    figures: dict[str, str]

    @property
    def args(self) -> list[str]:
        """The command's arguments after ``casadi-posture``."""
        return shlex.split(self.line)


def _simulate(name: str, figures: dict[str, str]) -> Command:
    """``simulate problems/NAME.toml`` (the gallery's command) without its report, writing
    to out/NAME; ``figures`` by the run's file name."""
    line = f"simulate problems/{name}.toml --no-report --out out/{name}"
    return Command(line, {f"out/{name}/{made}": place for made, place in figures.items()})


#: Every figure in docs/ and the command that makes it (the page that shows it says which).
COMMANDS: tuple[Command, ...] = (
    # docs/scenarios.md, docs/gallery.md: the paper's Fig. 3
    Command(
        "curve problems/frontal_elbow.toml --dof elbow_flexion --out out/fig3.png",
        {"out/fig3.png": "docs/frontal_elbow_fig3.png"},
    ),
    # docs/scenarios.md and docs/gallery.md: the 2-DOF arms
    _simulate(
        "holding_m45",
        {
            "fatigue.png": "docs/scenarios/holding_m45_fatigue.png",
            "postures.png": "docs/scenarios/holding_m45_postures.png",
        },
    ),
    _simulate("holding_m25", {"postures.png": "docs/gallery/holding_m25_postures.png"}),
    _simulate(
        "holding_horizontal", {"postures.png": "docs/gallery/holding_horizontal_postures.png"}
    ),
    _simulate(
        "holding_horizontal_work_rest",
        {"schedule.png": "docs/gallery/holding_horizontal_work_rest_schedule.png"},
    ),
    _simulate(
        "line_plane_hysteresis",
        {
            "fatigue.png": "docs/scenarios/line_plane_fatigue.png",
            "effector.png": "docs/scenarios/line_plane_effector.png",
            "postures.png": "docs/scenarios/line_plane_postures.png",
        },
    ),
    _simulate(
        "strategy_frontal_elbow",
        {"postures.png": "docs/gallery/strategy_frontal_elbow_postures.png"},
    ),
    _simulate(
        "strategy_shoulder_limit",
        {"active_torque.png": "docs/scenarios/shoulder_limit_active_torque.png"},
    ),
    _simulate(
        "strategy_extensors", {"active_torque.png": "docs/scenarios/extensors_active_torque.png"}
    ),
    # docs/scenarios.md, docs/gallery.md and the README: the standing wall; the workplaces
    _simulate(
        "standing_wall_horizontal",
        {"postures.png": "docs/scenarios/standing_wall_horizontal_postures.png"},
    ),
    *(
        _simulate(name, {"postures.png": f"docs/gallery/{name}_postures.png"})
        for name in (
            "standing_wall_m25",
            "standing_wall_m45",
            "standing_shelf_box",
            "standing_overhead_drill",
            "seated_assembly",
        )
    ),
    # docs/gallery.md and docs/motion.md: the recorded lift
    Command(
        "evaluate problems/recorded_box_transfer.toml --motion"
        " problems/recordings/box_transfer.c3d --no-report --out out/evaluate",
        {"out/evaluate/postures.png": "docs/gallery/recorded_box_transfer_postures.png"},
    ),
    # docs/whatif.md and docs/workflows.md
    Command(
        "whatif problems/holding_m45.toml --vary 'loads[0].mass_kg=1,2.5,5'"
        " --vary body.sex=male,female --static --quiet --no-report --out out/whatif/load-sex",
        {
            "out/whatif/load-sex/whatif_capable_pct_vs_loads_0_.mass_kg.png": (
                "docs/whatif_capable_pct_vs_load.png"
            )
        },
    ),
    Command(
        "whatif problems/holding_m45.toml --vary 'loads[0].mass_kg=1,2,3,4,5'"
        " --vary 'tasks[0].elevation_deg=0,-25,-45' --quiet --no-report"
        " --out out/whatif/load-angle",
        {
            "out/whatif/load-angle/whatif_task_held_s_vs_loads_0_.mass_kg.png": (
                "docs/whatif_task_held_vs_load.png"
            )
        },
    ),
    # docs/workflows.md
    Command(
        "sensitivity problems/holding_m45.toml --kind load --kind target --kind body"
        " --kind strength --top 8 --out out/sens",
        {"out/sens/tornado.png": "docs/sensitivity_tornado.png"},
    ),
    Command(
        "design problems/holding_horizontal.toml"
        " --free 'tasks[0].point_m[2],tasks[1].target_m[2]=-0.45:0.1' --out out/design",
        {"out/design/design.png": "docs/design_sweep.png"},
    ),
    Command(
        "duty-cycle problems/holding_horizontal.toml --t-off 30 --out out/duty",
        {"out/duty/duty_cycle.png": "docs/duty_cycle.png"},
    ),
    # docs/population.md
    Command(
        "population problems/standing_wall_horizontal.toml --n 20 --jobs 2 --out out/population",
        {"out/population/survival.png": "docs/population_survival.png"},
    ),
)


def figures() -> dict[str, Command]:
    """Each figure's place in the repository, and the command that makes it."""
    return {place: command for command in COMMANDS for place in command.figures.values()}


def run(command: Command, into: Path) -> float:
    """Run ``command`` in a fresh folder holding a copy of ``problems/`` and copy its
    figures to their places under ``into``; the wall time [s]. A command that ends with
    another code than 0 or 1, or does not write a figure, raises RuntimeError with its
    output."""
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="docs-figures-") as folder:
        shutil.copytree(ROOT / "problems", Path(folder) / "problems")
        done = subprocess.run(
            [sys.executable, "-m", "casadi_posture", *command.args],
            cwd=folder,
            capture_output=True,
            text=True,
            check=False,
        )
        missing = [made for made in command.figures if not (Path(folder) / made).is_file()]
        if done.returncode not in DREW or missing:
            raise RuntimeError(
                f"casadi-posture {command.line}: exit code {done.returncode}"
                f"{', did not write ' + ', '.join(missing) if missing else ''}\n"
                f"{done.stdout}{done.stderr}"
            )
        for made, place in command.figures.items():
            (into / place).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(Path(folder) / made, into / place)
    return time.perf_counter() - start


def make(places: Iterable[str], into: Path = ROOT, jobs: int = 2) -> list[tuple[Command, float]]:
    """Make the figures at ``places`` (all when empty) again, their commands ``jobs`` at
    a time, into ``into``; each command and its wall time [s], printed as each ends. The
    commands that failed raise one RuntimeError after the others have run."""
    known = figures()
    wanted = list(places) or list(known)
    unknown = [p for p in wanted if p not in known]
    if unknown:
        raise KeyError(f"no command makes {', '.join(unknown)}: expected one of {sorted(known)}")
    commands = list(dict.fromkeys(known[p] for p in wanted))

    def one(command: Command) -> tuple[Command, float]:
        seconds = run(command, into)
        print(f"{seconds:6.1f} s  casadi-posture {command.line}", flush=True)
        for place in command.figures.values():
            print(f"          -> {place}", flush=True)
        return command, seconds

    with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        futures = [pool.submit(one, command) for command in commands]
    failed = [str(f.exception()) for f in futures if f.exception() is not None]
    if failed:
        raise RuntimeError("\n".join(failed))
    return [f.result() for f in futures]


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m docs.generate.figures [FIGURE ...] [--jobs N]``: exit 2 for a figure no
    command makes, 1 for a command that failed, 130 on Ctrl-C."""
    parser = argparse.ArgumentParser(prog="python -m docs.generate.figures", description=__doc__)
    parser.add_argument("figures", nargs="*", help="docs/... .png (default: every figure)")
    parser.add_argument("--jobs", type=int, default=2, help="commands run at once (default 2)")
    options = parser.parse_args(argv)
    start = time.perf_counter()
    try:
        made = make(options.figures, jobs=options.jobs)
    except KeyError as error:
        print(f"docs figures: {error.args[0]}", file=sys.stderr)
        return 2
    except RuntimeError as error:
        print(f"docs figures: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("docs figures: interrupted (Ctrl-C)", file=sys.stderr)
        return 130
    count = sum(len(command.figures) for command, _ in made)
    print(
        f"figures made: {count}, by {len(made)} commands, {time.perf_counter() - start:.0f} s wall"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
