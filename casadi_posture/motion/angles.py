"""Joint-angle recordings: a CSV or Parquet table with a time column [s] and one column per DOF
in degrees, named as ``describe`` names the DOFs (``shoulder_flexion_r`` or
``shoulder_flexion_r_deg``, as timeline.csv has them) or mapped by the problem's
``[motion.columns]`` (docs/motion.md)."""

from __future__ import annotations

import csv
import difflib
import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from casadi_posture.body.tree import BodyModel
from casadi_posture.errors import MISSING, ProblemError
from casadi_posture.motion.recording import Recording, check_times, fill_gaps
from casadi_posture.spec.schema import MotionSpec

#: The names a time column may have, tried in this order.
TIME_COLUMNS = ("time_s", "time")
#: Below this largest |angle| [deg] over every DOF column a table looks like radians (π).
RADIANS_BELOW_DEG = math.pi
#: A column this similar to a DOF's name (difflib's ratio) is taken for a misspelt DOF.
TYPO_SIMILARITY = 0.85
#: Outside its range by more than this [deg], a DOF's recorded angle is flagged.
RANGE_SLACK_DEG = 1.0
#: Beyond this |angle| [deg] a value is not a joint's angle in degrees: another unit.
MAX_ANGLE_DEG = 360.0


def read_table(path: Path) -> dict[str, np.ndarray | list[str]]:
    """A CSV (comma-separated, a header row) or Parquet file's columns by name: numbers as
    float arrays (an empty cell NaN), other columns as their text."""
    if not path.is_file():
        raise ProblemError(path, None, None, "a recording file that exists")
    if path.suffix.lower() == ".parquet":
        return _parquet(path)
    if path.suffix.lower() != ".csv":
        raise ProblemError(path, None, None, "a .csv or .parquet file of joint angles")
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:
            rows = list(csv.reader(handle))
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise ProblemError(path, None, None, f"a readable CSV file ({error})") from None
    rows = [r for r in rows if any(cell.strip() for cell in r)]
    if len(rows) < 2:
        raise ProblemError(path, None, None, "a header row and at least one row of frames")
    header = [h.strip() for h in rows[0]]
    columns: dict[str, np.ndarray | list[str]] = {}
    for j, name in enumerate(header):
        if not name or name in columns:
            expected = "a unique, non-empty name for every column"
            raise ProblemError(path, f"column {j + 1}", name, expected)
        cells = [r[j].strip() if j < len(r) else "" for r in rows[1:]]
        numbers = _numbers(cells)
        columns[name] = cells if numbers is None else numbers
    return columns


def _numbers(cells: list[str]) -> np.ndarray | None:
    """The cells as floats (empty: NaN), or None when one is not a number."""
    try:
        return np.array([float(c) if c else math.nan for c in cells])
    except ValueError:
        return None


def _parquet(path: Path) -> dict[str, np.ndarray | list[str]]:
    try:
        import pyarrow.parquet as pq
    except ImportError:
        expected = "pyarrow to read Parquet (pip install 'casadi_posture[parquet]'), or a CSV file"
        raise ProblemError(path, None, None, expected) from None
    try:
        table = pq.read_table(str(path))
    except Exception as error:  # pyarrow raises several kinds on a file that is not Parquet
        raise ProblemError(path, None, None, f"a readable Parquet file ({error})") from None
    out: dict[str, np.ndarray | list[str]] = {}
    for name in table.column_names:
        values = table.column(name).to_pylist()
        numeric = all(v is None or isinstance(v, int | float) for v in values)
        out[name] = (
            np.array([math.nan if v is None else float(v) for v in values])
            if numeric
            else [str(v) for v in values]
        )
    return out


def read_angles(
    path: Path, body: BodyModel, spec: MotionSpec, posture: np.ndarray, problem: Path
) -> Recording:
    """The joint-angle recording ``path`` on ``body``, with the problem file ``problem``'s
    ``[motion]`` (``spec``): columns mapped to DOFs, angles in degrees converted to radians,
    NaN gaps filled (up to ``max_gap_s`` noted, longer ones flagged), angles outside the
    body's range flagged; with ``hold_missing``, a DOF without a column held at ``posture``
    [rad]. Every bad column, cell or frame is a one-line error."""
    table = read_table(path)
    time_name = next((n for n in TIME_COLUMNS if n in table), None)
    if time_name is None:
        raise ProblemError(path, "time_s", None, f"a time column in s, named one of {TIME_COLUMNS}")
    time = _numeric(table, time_name, path)
    check_times(time, path, time_name)
    dofs, ignored = _dof_columns(table, body, spec, path, problem, time_name)
    missing = [d for d in body.dof_names if d not in dofs.values()]
    if missing and not spec.hold_missing:
        more = f" and {len(missing) - 6} more" if len(missing) > 6 else ""
        shown = ", ".join(missing[:6]) + more
        unused = f"; columns not used: {', '.join(ignored[:5])}, map them in [motion.columns]"
        expected = (
            f"a column for every DOF of the body ({len(missing)} missing: {shown}); or "
            "motion.hold_missing = true in the problem file to hold them at its posture_deg"
            + (unused if ignored else "")
        )
        raise ProblemError(path, missing[0], MISSING, expected)
    degrees = {dof: _numeric(table, column, path) for column, dof in dofs.items()}
    _check_not_radians(degrees, path)
    _check_within_a_turn(degrees, {d: c for c, d in dofs.items()}, path)
    q = np.empty((time.size, len(body.dofs)))
    notes, flags = [], []
    filled_runs = 0
    for column, dof in dofs.items():
        try:
            values, short, long = fill_gaps(degrees[dof], time, spec.max_gap_s)
        except ValueError:
            raise ProblemError(path, column, "all empty", "angles in degrees") from None
        filled_runs += len(short)
        for first, last in long:
            flags.append(
                f"{column}: frames {first + 1}-{last + 1} ({time[first]:g}-{time[last]:g} s) "
                f"missing for longer than motion.max_gap_s = {spec.max_gap_s:g} s, filled "
                "linearly: the answer there is not measured"
            )
        q[:, body.index[dof]] = np.radians(values)
    if filled_runs:
        notes.append(
            f"{filled_runs} gap(s) of at most {spec.max_gap_s:g} s filled by linear interpolation"
        )
    for dof in missing:
        q[:, body.index[dof]] = posture[body.index[dof]]
    if missing:
        notes.append(f"{len(missing)} DOF(s) not in the file, held at the problem's posture")
    if ignored:
        more = f" and {len(ignored) - 5} more" if len(ignored) > 5 else ""
        notes.append(f"{len(ignored)} column(s) ignored, not a DOF: {', '.join(ignored[:5])}{more}")
    flags += _out_of_range(q, time, body, {d: c for c, d in dofs.items()})
    return Recording(path, "angles", time, q, tuple(notes), tuple(flags))


def _numeric(table: Mapping[str, np.ndarray | list[str]], column: str, path: Path) -> np.ndarray:
    """A column's numbers; a text cell is a one-line error naming its frame."""
    values = table[column]
    if isinstance(values, np.ndarray):
        if np.isinf(values).any():
            frame = int(np.flatnonzero(np.isinf(values))[0]) + 1
            raise ProblemError(path, f"{column} (frame {frame})", "inf", "a finite number")
        return values
    frame, cell = next((i, c) for i, c in enumerate(values, start=1) if _numbers([c]) is None)
    raise ProblemError(path, f"{column} (frame {frame})", cell, "a number")


def _dof_columns(
    table: Mapping[str, object],
    body: BodyModel,
    spec: MotionSpec,
    path: Path,
    problem: Path,
    time_name: str,
) -> tuple[dict[str, str], list[str]]:
    """The file's DOF columns (column name → DOF) and the columns ignored: a column named
    as a DOF (with or without ``_deg``) or mapped by ``[motion.columns]`` is one; one nearly
    so named is a one-line error (a misspelt DOF); any other is ignored."""
    for column, dof in spec.columns.items():
        if dof not in body.index:
            expected = f"a DOF of the body: {closest(dof, body.dof_names)}"
            raise ProblemError(problem, f"motion.columns.{column}", dof, expected)
        if column not in table:
            expected = f"a column of {path} ({closest(column, list(table))})"
            raise ProblemError(problem, f"motion.columns.{column}", dof, expected)
    dofs: dict[str, str] = {}
    ignored: list[str] = []
    for column in table:
        if column == time_name:
            continue
        stem = column.removesuffix("_deg")
        if column in spec.columns:
            dof = spec.columns[column]
        elif stem in body.index:
            dof = stem
        elif difflib.get_close_matches(stem, body.dof_names, n=1, cutoff=TYPO_SIMILARITY):
            close = closest(stem, body.dof_names)
            expected = f"a column named after a DOF of the body: {close}"
            raise ProblemError(path, column, None, expected)
        else:
            ignored.append(column)
            continue
        if dof in dofs.values():
            other = next(c for c, d in dofs.items() if d == dof)
            raise ProblemError(path, column, dof, f"one column per DOF ({other!r} is {dof} too)")
        dofs[column] = dof
    return dofs, ignored


def closest(name: str, choices: list[str]) -> str:
    """'did you mean' words for ``name`` among ``choices``."""
    close = difflib.get_close_matches(name, choices, n=1)
    return f"did you mean {close[0]!r}?" if close else f"one of {', '.join(choices[:8])}, ..."


def _check_not_radians(degrees: Mapping[str, np.ndarray], path: Path) -> None:
    """Angles in degrees: a table of several DOFs whose every |angle| is below π looks like
    radians, a one-line error."""
    if len(degrees) < 3:
        return
    largest = max(
        (float(np.nanmax(np.abs(v))) for v in degrees.values() if np.isfinite(v).any()),
        default=0.0,
    )
    if largest < RADIANS_BELOW_DEG:
        column = next(iter(degrees))
        expected = (
            f"angles in degrees: no DOF moves beyond {largest:.3g}, which looks like radians "
            "(multiply by 57.2958)"
        )
        raise ProblemError(path, column, largest, expected)


def _check_within_a_turn(
    degrees: Mapping[str, np.ndarray], columns: Mapping[str, str], path: Path
) -> None:
    """Angles [deg] (by DOF, from the file's ``columns``) within ±``MAX_ANGLE_DEG``; the first
    beyond, in another unit (millidegrees: angles × 1000), is a one-line error naming its
    column and frame."""
    for dof, values in degrees.items():
        over = np.flatnonzero(np.abs(values) > MAX_ANGLE_DEG)
        if over.size:
            k = int(over[0])
            expected = f"an angle in degrees within ±{MAX_ANGLE_DEG:g}° (another unit?)"
            raise ProblemError(path, f"{columns[dof]} (frame {k + 1})", float(values[k]), expected)


def _out_of_range(
    q: np.ndarray, time: np.ndarray, body: BodyModel, columns: Mapping[str, str]
) -> list[str]:
    """A flag per DOF whose recorded angle leaves the body's range by more than
    ``RANGE_SLACK_DEG``: its passive torque there is the model's extrapolation."""
    out = []
    slack = math.radians(RANGE_SLACK_DEG)
    for dof, column in columns.items():
        d = body.dofs[body.index[dof]]
        values = q[:, body.index[dof]]
        outside = (values < d.lower - slack) | (values > d.upper + slack)
        if outside.any():
            k = int(np.argmax(np.abs(np.clip(values, d.lower, d.upper) - values)))
            out.append(
                f"{column}: {math.degrees(values[k]):.1f}° at {time[k]:g} s is outside the "
                f"body's range [{math.degrees(d.lower):.0f}, {math.degrees(d.upper):.0f}]° "
                f"for {int(outside.sum())} frame(s): the passive torque there is extrapolated"
            )
    return out
