"""The Python API: load a problem, look at it, solve it, simulate it, compare the solvers,
run what-if grids and batches. The command line is a thin layer over these functions.

Every result is a small named type whose data turns into a pandas DataFrame in one call
(``to_frame()``; pandas is an optional extra), with the columns and units of the files:
degrees, N·m, %MVC, s. The modules that draw (matplotlib, a third of a second to import)
are imported where a figure or page is drawn, so that a command that draws nothing, or
draws in other processes, never loads them (``casadi_posture.output``).

    >>> import casadi_posture as cp
    >>> problem = cp.load("problems/holding_m45.toml", {"loads[0].mass_kg": 5.0})
    >>> answer = cp.solve(problem)
    >>> answer.limiting.name, round(answer.limiting.endurance_min, 2)
    ('shoulder_flexors', 1.46)
"""

from __future__ import annotations

import hashlib
import shutil
import tomllib
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from casadi_posture.biomech.curve import TorqueCurve, torque_curve
from casadi_posture.description import description
from casadi_posture.errors import MISSING, ProblemError
from casadi_posture.frames import frame
from casadi_posture.ik.solvers import check_solver
from casadi_posture.motion.angles import read_angles
from casadi_posture.motion.bvh import read_bvh
from casadi_posture.motion.marker_ik import read_c3d_recording
from casadi_posture.motion.markers import read_c3d
from casadi_posture.motion.recording import Recording, between, held_frames, repeat, resample
from casadi_posture.motion.scaling import body_lengths, lengths_note, measured_lengths
from casadi_posture.output.answer import answer_json
from casadi_posture.output.axes import axis_keys, axis_label
from casadi_posture.output.movie_formats import check_format
from casadi_posture.output.plain import dumps, plain
from casadi_posture.output.results import (
    event_columns,
    summary,
    timeline_columns,
    write_table,
)
from casadi_posture.output.rows import simulation_row
from casadi_posture.output.run_files import write_run
from casadi_posture.output.writable import check_writable
from casadi_posture.problem import (
    Problem,
    load_problem,
    problem_from_data,
    read_problem_text,
    text_sha256,
)
from casadi_posture.runs import compare as comparison
from casadi_posture.runs.batch import BatchReport, cases_from_paths, clear_run, run_batch
from casadi_posture.runs.grid_report import PAGE, write_grid_report
from casadi_posture.runs.population import (
    MAX_WORKERS,
    POPULATION_OUTPUTS,
    PopulationReport,
    run_population,
)
from casadi_posture.runs.whatif import MAX_CASES, WHATIF_OUTPUTS, describe_grid, grid
from casadi_posture.simulation import SimulationResult, replay
from casadi_posture.simulation import simulate as run_simulation
from casadi_posture.static import StaticAnswer, at_posture
from casadi_posture.static import solve as solve_static


def load(path: str | Path, overrides: Mapping[str, Any] | None = None) -> Problem:
    """A problem file, validated and resolved; ``overrides`` set dotted keys first
    (``{"loads[0].mass_kg": 5.0, "fatigue.strategy": "passive"}``). Bad input raises
    ``ProblemError`` naming the file, the key, the value and what was expected."""
    return load_problem(path, overrides)


def loads(text: str, name: str = "<text>", overrides: Mapping[str, Any] | None = None) -> Problem:
    """A problem from TOML text; ``name`` names it in messages."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ProblemError(name, None, None, f"valid TOML ({error})") from None
    return from_dict(data, name, overrides)


def from_dict(
    data: Mapping[str, Any], name: str = "<dict>", overrides: Mapping[str, Any] | None = None
) -> Problem:
    """A problem from plain data: the tables of a problem file as a dict."""
    return problem_from_data(data, name, overrides)


def describe(problem: Problem) -> dict[str, Any]:
    """The resolved model as plain data: DOFs, segments, loads, tasks, every parameter with
    its unit, source and status (what ``casadi-posture describe --json`` prints)."""
    return description(problem)


def torques(problem: Problem, posture_deg: Mapping[str, float] | None = None) -> StaticAnswer:
    """Torques, loads and endurances at the problem's posture, or with some DOFs set to
    ``posture_deg`` [deg]."""
    if posture_deg:
        problem = problem.with_posture(dict(posture_deg), key="posture_deg")
    return at_posture(problem)


def curve(
    problem: Problem, dof: str, posture_deg: Mapping[str, float] | None = None
) -> TorqueCurve:
    """τe, τp and τa [N·m] of ``dof`` over its whole range, the other DOFs held at the
    problem's posture or at ``posture_deg`` [deg], and the angles where τa is zero (the
    paper's Fig. 3). ``curve.to_frame()`` and ``curve.zeros_frame()`` give them in degrees."""
    if posture_deg:
        problem = problem.with_posture(dict(posture_deg), key="posture_deg")
    if dof not in problem.body.index:
        raise ProblemError(problem.path, "dof", dof, f"one of {problem.body.dof_names}")
    return torque_curve(problem.torque_model(), problem.posture, dof)


def plot_curve(
    result: TorqueCurve, path: str | Path, *, title: str | None = None, force: bool = False
) -> Path:
    """Draw a ``curve`` as the paper's Fig. 3 into ``path`` (.png, .pdf, .svg, ...):
    a new file, or any with ``force``."""
    from casadi_posture.output.plots import plot_torque_curve  # imported when drawn

    path = Path(path)
    check_figure(path, force=force, key="path")
    return plot_torque_curve(result, path, title or f"torques over {result.dof}")


def check_figure(path: Path, *, force: bool, key: str, source: str | Path | None = None) -> None:
    """A figure's path: a format matplotlib writes, and the rule of every output."""
    from casadi_posture.output.plots import figure_formats  # imported when drawn

    formats = figure_formats()
    if path.suffix.lstrip(".").lower() not in formats:
        expected = f"a figure file ending in one of {', '.join('.' + f for f in sorted(formats))}"
        raise ProblemError(source, key, str(path), expected)
    check_out(path, force=force, key=key, folder=False)


def solve(problem: Problem, solver: str | None = None) -> StaticAnswer:
    """The prioritized IK from the problem's posture (``solver``: ``"nullspace"`` or
    ``"lexicographic"``, default the file's), with the torques at the solution;
    ``answer.flags`` say why the answer cannot be used as it is (empty: it can)."""
    check_solver(solver, problem.path)
    return solve_static(problem, solver)


@dataclass(frozen=True)
class Simulation:
    """A simulated hold: ``result`` holds the timeline [rad inside], the events and why it
    stopped; the methods give it in the files' units."""

    result: SimulationResult

    def __repr__(self) -> str:
        return f"Simulation({self.result!r})"

    @property
    def stop(self) -> str:
        """Why the run ended: completed, exhausted, never_held or interrupted."""
        return self.result.stop

    def summary(self) -> dict[str, Any]:
        """What the run found, as summary.json holds it (None: an unlimited endurance, a
        time that never came)."""
        return plain(summary(self.result))

    def row(self) -> dict[str, Any]:
        """The outcomes as one flat row, as a batch or what-if table holds them (None: an
        unlimited endurance, a time that never came)."""
        return plain(simulation_row(self.result))

    def to_frame(self) -> Any:
        """The timeline as a pandas DataFrame, the columns of timeline.csv."""
        return frame(timeline_columns(self.result))

    def events_frame(self) -> Any:
        """The events as a pandas DataFrame, the columns of events.csv."""
        return frame(event_columns(self.result))

    def write(
        self,
        out: str | Path,
        *,
        figures: bool = True,
        report: bool = True,
        force: bool = False,
        workers: int = 1,
    ) -> list[Path]:
        """Write the run's files (and figures, and report.html: the run in a browser) into
        ``out``: a new or empty folder, or any folder with ``force``; ``workers`` > 1
        writes them side by side in that many processes forked from this one."""
        out = Path(out)
        check_out(out, force=force, key="out")
        written = write_run(self.result, out, figures=figures, report=report, workers=workers)
        if written.report_missing is not None:
            warnings.warn(f"report.html not written: {written.report_missing}", stacklevel=2)
        return written.paths

    def animate(self, path: str | Path, *, force: bool = False) -> Path | None:
        """Animate the run into ``path``: .gif (always) or .mp4 (with ffmpeg on the PATH); a
        new file, or any with ``force``. None when Ctrl-C stopped it (no file is left)."""
        path = Path(path)
        check_format(path.suffix.lstrip(".").lower(), key="path")
        check_out(path, force=force, key="path", folder=False)
        from casadi_posture.output.animation import write_animation  # imported when drawn

        return write_animation(self.result, path)


def simulate(problem: Problem, solver: str | None = None) -> Simulation:
    """Simulate holding the problem's tasks for ``simulation.duration_s``: fatigue, the
    fatigue-reducing constraint with its hysteresis, recovery. Ctrl-C stops it between two
    steps with the steps run so far (``stop == "interrupted"``)."""
    check_solver(solver, problem.path)
    return Simulation(run_simulation(problem, solver))


def read_motion(
    problem: Problem,
    motion: str | Path,
    *,
    solver: str | None = None,
    between_s: tuple[float, float] | None = None,
    resample_s: float | None = None,
    repeat_times: int | None = None,
    until_s: float | None = None,
) -> Recording:
    """A recorded motion on the problem's body (docs/motion.md): a CSV or Parquet file of
    joint angles [deg] with a time column [s]; a C3D file of markers or a BVH file of joint
    rotations, turned into joint angles by the IK ``solver`` (default: the file's) with the
    problem's ``[motion.markers]`` or ``[motion.bvh]``; each load held in its
    ``motion.held_s`` windows; cut to the frames ``between_s`` (start and end [s], the file's
    time) if given, resampled every ``resample_s`` [s] if given, then played
    ``repeat_times`` times or until ``until_s`` [s] as a work cycle."""
    path, spec = Path(motion), problem.spec.motion
    check_solver(solver, problem.path)
    ik = {
        "solver_name": solver or problem.spec.solver.name,
        "problem": problem.path,
        "solver_spec": problem.spec.solver if solver is None else None,
    }  # the file's solver options are for the file's solver
    kind, lengths = path.suffix.lower(), None
    if kind == ".c3d":
        markers = read_c3d(path)
        if spec.scale_segments:
            lengths = measured_lengths(
                markers,
                problem.body,
                spec.markers,
                spec.scale_segments,
                spec.calibrate_s,
                problem.path,
            )
            before = body_lengths(problem.body, spec.scale_segments)
            problem = scaled(problem, lengths)
        recording, _ = read_c3d_recording(markers, problem.body, spec, problem.posture, **ik)
        if lengths:
            notes = (*recording.notes, lengths_note(lengths, before))
            recording = replace(recording, notes=notes, segment_lengths_m=lengths)
    elif kind == ".bvh":
        recording = read_bvh(path, problem.body, spec.bvh, problem.posture, **ik)
    else:
        recording = read_angles(path, problem.body, spec, problem.posture, problem.path)
    names = [load.name for load in problem.loads]
    held = held_frames(recording.time, spec.held_s, names, problem.path)
    options = {
        "solver": solver,
        "between_s": None if between_s is None else list(between_s),
        "resample_s": resample_s,
        "repeat_times": repeat_times,
        "until_s": until_s,
    }
    sha256 = hashlib.sha256(path.read_bytes()).hexdigest()
    recording = replace(recording, held=held, read_with={"sha256": sha256, **options})
    if between_s is not None:
        recording = between(recording, *between_s)
    if resample_s is not None:
        recording = resample(recording, resample_s)
    if repeat_times is not None or until_s is not None:
        recording = repeat(recording, times=repeat_times, until_s=until_s)
    return recording


def evaluate(
    problem: Problem,
    motion: str | Path | Recording,
    *,
    solver: str | None = None,
    between_s: tuple[float, float] | None = None,
    resample_s: float | None = None,
    repeat_times: int | None = None,
    until_s: float | None = None,
) -> Simulation:
    """The problem's body driven by a recorded motion instead of the IK: the torques, loads,
    fatigue, recovery, low back and RULA/REBA of every frame, as ``simulate`` gives them for
    predicted postures (``motion``: a file, read by ``read_motion`` with the other
    arguments, or a ``Recording``; ``solver`` the marker IK's of a C3D file). Nothing moves
    the posture: a group the model finds exhausted is an event and a flag, and the
    recording goes on."""
    if isinstance(motion, Recording):
        recording = motion
    else:
        recording = read_motion(
            problem,
            motion,
            solver=solver,
            between_s=between_s,
            resample_s=resample_s,
            repeat_times=repeat_times,
            until_s=until_s,
        )
    if recording.segment_lengths_m:
        problem = scaled(problem, recording.segment_lengths_m)
    return Simulation(replay(problem, recording))


def scaled(problem: Problem, lengths: Mapping[str, float]) -> Problem:
    """``problem`` with its segments at ``lengths`` [m] (segment name → length): a body
    scaled to a recorded subject."""
    return problem.with_overrides({f"body.segments.{n}.length_m": v for n, v in lengths.items()})


def write_solve(
    answer: StaticAnswer, out: str | Path, *, report: bool = True, force: bool = False
) -> list[Path]:
    """Write a solved ``answer`` into ``out`` (a new or empty folder, or any with
    ``force``): solve.json (what ``solve --json`` prints) and, with ``report``, report.html
    (the start and the answer in 3-D, the summary, the loads: one page for a browser)."""
    out = Path(out)
    check_out(out, force=force, key="out")
    out.mkdir(parents=True, exist_ok=True)
    path = out / "solve.json"
    path.write_text(dumps(answer_json(answer, str(answer.problem.path))) + "\n", encoding="utf-8")
    if not report:
        return [path]
    from casadi_posture.output.posture_page import write_solve_page  # imported when drawn

    return [path, write_solve_page(answer, out / "report.html")]


def compare(problem: Problem, starts: int = 0, seed: int = 0) -> comparison.Comparison:
    """Both IK solvers from the same start, and a verdict on whether they agree (an answer
    both share that misses a level: a local minimum, or a target out of reach, and on which
    evidence); with ``starts``, also from that many random starts within the joint limits
    (seeded by ``seed``), summed up in ``.starts``."""
    return comparison.compare(problem, starts, seed)


def write_compare(
    compared: Sequence[tuple[Problem, comparison.Comparison, Sequence[str]]],
    out: str | Path,
    *,
    report: bool = True,
    force: bool = False,
) -> list[Path]:
    """Write comparisons into ``out`` (a new or empty folder, or any with ``force``):
    compare.csv (a row per problem and level) and, with ``report``, report.html (a row per
    problem; a click shows its start and both solvers' postures). ``compared``: each
    problem, its comparison and its flags (lines; none when it can be used as it is)."""
    out = Path(out)
    check_out(out, force=force, key="out")
    out.mkdir(parents=True, exist_ok=True)
    table_rows = [row for _, c, _ in compared for row in comparison.rows(c)]
    columns = {k: [r[k] for r in table_rows] for k in (table_rows[0] if table_rows else {})}
    write_table(columns, out / "compare.csv")
    written = [out / "compare.csv"]
    if report and compared:
        from casadi_posture.runs.compare_report import write_compare_page  # imported when drawn

        written.append(write_compare_page(compared, out / "report.html"))
    return written


def whatif(
    problem: str | Path | Problem,
    vary: Mapping[str, Sequence[Any]],
    out: str | Path,
    *,
    static: bool = False,
    paired: bool = False,
    solver: str | None = None,
    jobs: int = 1,
    scheduler: str | None = None,
    resume: bool = False,
    force: bool = False,
    max_cases: int = MAX_CASES,
    overrides: Mapping[str, Any] | None = None,
    figures: bool = True,
    report: bool = True,
    quiet: bool = True,
) -> BatchReport:
    """A what-if study: the problem with each combination of the ``vary`` values (a full
    grid; with ``paired``, the i-th values of every key together), static (torques at the
    start) or simulated, run into ``out``; ``overrides`` apply to every case first. A key
    ``"KEY1,KEY2"`` ties keys of one unit to one value per case (both hands' heights) and
    counts as one axis. ``report.to_frame()`` is the table (also ``whatif.csv``);
    ``report.figures`` draw each answer against the first axis, one line per value of the
    others; with ``report`` each simulated case gets its report.html and ``out`` one page
    of the grid (report.html: the table, sortable, and the figures).

    ``problem`` is a file, or a ``Problem`` loaded from one (its overrides are kept):
    every case is rebuilt from the file where it runs. With ``jobs`` > 1 a script must
    start its work under ``if __name__ == "__main__":`` (worker processes import it)."""
    path, given = _problem_file(problem, overrides)
    if not vary:
        raise ProblemError(path, "vary", MISSING, "at least one key to vary")
    varies = [(",".join(axis_keys(axis, path)), list(values)) for axis, values in vary.items()]
    cases = grid(
        path,
        varies,
        solver=solver,
        simulate=not static,
        max_cases=max_cases,
        paired=paired,
        base=given,
    )
    cases = [replace(case, report=report) for case in cases]
    described = describe_grid(path, varies, solver=solver, simulate=not static)
    described |= {"paired": paired, "overrides": given}
    out = Path(out)
    prepare_runs(out, resume=resume, force=force, inputs=[path], outputs=WHATIF_OUTPUTS)
    answer = run_batch(
        cases, out, jobs=jobs, scheduler=scheduler, resume=resume, quiet=quiet, describe=described
    )
    shutil.copyfile(answer.summary, out / "whatif.csv")
    if figures:
        from casadi_posture.runs.whatif_plots import plot_outcomes  # imported when drawn

        data = load_problem(path, given).data
        labels = {axis: axis_label(data, axis) for axis, _ in varies}
        drawn = plot_outcomes(answer.rows, varies, labels, out, simulate=not static, paired=paired)
        answer = replace(answer, figures=tuple(drawn))
    if report:
        keys = ", ".join(axis for axis, _ in varies)
        write_grid_report(answer, out, f"What if: {path} with {keys} varied", answer.figures)
    return answer


def batch(
    problems: str | Path | Sequence[str | Path],
    out: str | Path,
    *,
    solver: str | None = None,
    jobs: int = 1,
    scheduler: str | None = None,
    resume: bool = False,
    force: bool = False,
    overrides: Mapping[str, Any] | None = None,
    report: bool = True,
    quiet: bool = True,
) -> BatchReport:
    """Simulate many problem files (a file, a folder of ``*.toml`` files, or a list of
    both) into ``out``; ``overrides`` apply to every file; with ``report`` each case gets
    its report.html and ``out`` a page of every case's row (report.html). With ``jobs`` > 1
    a script must start its work under ``if __name__ == "__main__":``."""
    paths = [str(problems)] if isinstance(problems, str | Path) else [str(p) for p in problems]
    given = dict(overrides or {})
    cases = [
        replace(case, overrides=given, report=report) for case in cases_from_paths(paths, solver)
    ]
    out = Path(out)
    prepare_runs(out, resume=resume, force=force, inputs=[c.problem for c in cases], outputs=[PAGE])
    described = {"kind": "batch", "problems": paths, "solver": solver, "overrides": given}
    answer = run_batch(
        cases, out, jobs=jobs, scheduler=scheduler, resume=resume, quiet=quiet, describe=described
    )
    if report:
        write_grid_report(answer, out, f"Batch: {', '.join(paths)}")
    return answer


def population(
    problem: str | Path,
    out: str | Path,
    *,
    n: int,
    sexes: Sequence[str] = ("male", "female"),
    seed: int = 1,
    correlation: float | None = None,
    solver: str | None = None,
    jobs: int = 1,
    scheduler: str | None = None,
    resume: bool = False,
    force: bool = False,
    files: bool = False,
    max_cases: int = MAX_WORKERS,
    overrides: Mapping[str, Any] | None = None,
    quiet: bool = True,
) -> PopulationReport:
    """``n`` virtual workers of each of ``sexes`` (docs/population.md), drawn for ``seed``,
    each holding the problem's task on a body of their own sex, stature, mass and
    strengths, run as batch cases into ``out`` (resumable; ``jobs`` local processes or a
    Dask ``scheduler``; per worker only its summary row unless ``files``); writes
    population.json (the share of each sex still holding at 1, 2, 5, 10 and 20 minutes
    with 95 % intervals) and its figures. With ``jobs`` > 1 a script must start its work
    under ``if __name__ == "__main__":``."""
    path = Path(problem)
    check_solver(solver, path)
    unknown = [s for s in sexes if s not in ("male", "female")]
    if unknown or not sexes:
        raise ProblemError(path, "--sex", unknown or list(sexes), "male, female or both")
    text = read_problem_text(path)
    resolved = load_problem(path, overrides, text=text)
    out = Path(out)
    prepare_runs(out, resume=resume, force=force, inputs=[path], outputs=POPULATION_OUTPUTS)
    return run_population(
        resolved,
        text,
        out,
        n=n,
        sexes=tuple(sexes),
        seed=seed,
        correlation=correlation,
        solver=solver,
        jobs=jobs,
        scheduler=scheduler,
        resume=resume,
        files=files,
        max_cases=max_cases,
        quiet=quiet,
    )


def _problem_file(
    problem: str | Path | Problem, overrides: Mapping[str, Any] | None
) -> tuple[str, dict[str, Any]]:
    """The file a what-if runs from, and the overrides every case starts with: a
    ``Problem`` stands for its file and its own overrides, if the file still holds
    the text it was loaded from."""
    if not isinstance(problem, Problem):
        return str(problem), dict(overrides or {})
    path = problem.path
    unchanged = path.is_file() and problem.text_sha256 == text_sha256(read_problem_text(path))
    if not unchanged:
        raise ProblemError(
            path,
            "problem",
            MISSING,
            "a problem file, or a Problem loaded from a file that has not changed since",
        )
    return str(path), dict(problem.overrides) | dict(overrides or {})


def check_out(out: Path, *, force: bool, key: str = "--out", folder: bool = True) -> None:
    """The rule for every output: a new or empty folder (or, not ``folder``, a new file),
    unless ``force``; never the current folder or one that holds it; a path the file system
    lets us write."""
    check_out_name(out, key, folder=folder)
    if force or not out.exists():
        return
    if out.is_dir() and not any(out.iterdir()):
        return
    raise ProblemError(out, key, MISSING, "a new or empty output, or --force to overwrite it")


def check_out_name(out: Path, key: str = "--out", *, folder: bool = True) -> None:
    """An output is never the current folder or one that holds it, and is a ``folder`` (else
    a file) the file system lets us write (``check_writable``)."""
    check_writable(out, key, folder=folder)
    here = Path.cwd().resolve()
    if str(out) in ("", ".") or out.resolve() in (here, *here.parents):
        expected = "a folder or file name (not the current folder or one that holds it)"
        raise ProblemError(None, key, str(out), expected)


def prepare_runs(
    out: Path,
    *,
    resume: bool,
    force: bool,
    inputs: Sequence[str | Path] = (),
    outputs: Sequence[str] = (),
) -> None:
    """A batch's folder: continued with ``resume``, started over with ``force`` (the
    earlier run's files deleted: its cases, ``run.json``, its summary and the names or
    patterns in ``outputs``, nothing else), else new or empty. It may hold none of the
    ``inputs`` (the problem files)."""
    if resume and force:
        raise ProblemError(out, "--resume", MISSING, "either --resume or --force, not both")
    check_out_name(out)
    inside = [p for p in map(Path, inputs) if out.resolve() in Path(p).resolve().parents]
    if inside:
        raise ProblemError(
            out, "--out", MISSING, f"a folder apart from the problem files (it holds {inside[0]})"
        )
    if resume:
        return
    if force:
        clear_run(out, outputs)
        return
    try:
        check_out(out, force=False)
    except ProblemError:
        raise ProblemError(
            out,
            "--out",
            MISSING,
            "a new or empty folder, --resume to continue its run or --force to start over",
        ) from None
