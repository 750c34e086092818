"""A recorded motion on a body's DOFs, and what can be done to its frames before it drives the
body: gaps filled, resampled to a step, repeated as a work cycle (docs/motion.md)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from casadi_posture.errors import ProblemError
from casadi_posture.spec.schema import MAX_DURATION_S, MAX_STEPS


@dataclass(frozen=True)
class Recording:
    """Frames of a recorded motion: ``time`` [s] strictly increasing, as in the file;
    ``q`` [rad], one row per frame in the body's DOF order; the file and its kind; what
    reading did to the frames (``notes``, e.g. gaps filled) and why an answer on them needs
    care (``flags``, e.g. a long gap, angles outside the body's range); which loads each
    frame holds (``held``, from the problem's ``motion.held_s``)."""

    source: Path
    kind: str
    time: np.ndarray
    q: np.ndarray
    notes: tuple[str, ...] = ()
    flags: tuple[str, ...] = ()
    #: Per frame, whether each of the problem's loads is held (1) or not (0); None: all held.
    held: np.ndarray | None = None
    #: An IK fit's residuals per frame: per point, its distance from its markers [m] (C3D),
    #: or per joint, its segment's angle from the joint's orientation [rad] (BVH).
    residuals: dict[str, np.ndarray] | None = None
    #: How it was read, enough to read it again: the file's SHA-256 and the reader's options.
    read_with: dict[str, Any] | None = None
    #: Segment lengths [m] measured on the subject (``motion.scale_segments``), by segment
    #: name: ``evaluate`` builds the body with them.
    segment_lengths_m: dict[str, float] | None = None

    @property
    def frames(self) -> int:
        """The number of frames."""
        return int(self.time.size)

    @property
    def residual_unit(self) -> tuple[str, float]:
        """The unit the fit's ``residuals`` are given in outside, and its factor from them:
        degrees for a BVH file's joints, metres for markers."""
        return ("deg", 180 / math.pi) if self.kind == "bvh" else ("m", 1.0)

    @property
    def duration_s(self) -> float:
        """The time from the first frame to the last [s]."""
        return float(self.time[-1] - self.time[0])


def check_times(time: np.ndarray, source: Path, column: str) -> None:
    """Frame times [s]: finite and strictly increasing, at least two; else a one-line error
    naming the first bad frame (counted from 1, as a spreadsheet's data rows are)."""
    if time.size < 2:
        raise ProblemError(source, column, int(time.size), "at least two frames")
    bad = np.flatnonzero(~np.isfinite(time))
    if bad.size:
        frame = int(bad[0])
        raise ProblemError(source, f"{column} (frame {frame + 1})", "NaN", "a time in s")
    steps = np.diff(time)
    back = np.flatnonzero(steps <= 0)
    if back.size:
        frame = int(back[0]) + 1
        raise ProblemError(
            source,
            f"{column} (frame {frame + 1})",
            float(time[frame]),
            f"a time after the frame before ({time[frame - 1]:g} s): times strictly increasing",
        )
    if time[-1] - time[0] > MAX_DURATION_S:
        expected = f"a recording of at most {MAX_DURATION_S:g} s"
        raise ProblemError(source, column, float(time[-1] - time[0]), expected)


def between(recording: Recording, start_s: float, end_s: float) -> Recording:
    """The frames of ``recording`` from ``start_s`` to ``end_s`` [s] (the file's time), at
    least two: one phase of a longer recording."""
    key, window = "--between", [start_s, end_s]
    if not (math.isfinite(start_s) and math.isfinite(end_s) and start_s < end_s):
        raise ProblemError(None, key, window, "a start and a later end in s")
    inside = (recording.time >= start_s - 1e-9) & (recording.time <= end_s + 1e-9)
    if inside.sum() < 2:
        first, last = recording.time[0], recording.time[-1]
        expected = f"a window with 2 frames or more of the recording's {first:g} to {last:g} s"
        raise ProblemError(None, key, window, expected)
    held = None if recording.held is None else recording.held[inside]
    note = f"the frames from {start_s:g} to {end_s:g} s: {int(inside.sum())} of {recording.frames}"
    return replace(
        recording,
        time=recording.time[inside],
        q=recording.q[inside],
        held=held,
        residuals=_each(recording.residuals, lambda r: r[inside]),
        notes=(*recording.notes, note),
    )


def resample(recording: Recording, step_s: float) -> Recording:
    """The recording at every ``step_s`` [s] from its first frame to its last, each DOF
    interpolated linearly between the frames around it."""
    if not (math.isfinite(step_s) and step_s > 0):
        raise ProblemError(None, "--resample", step_s, "a step in s above 0")
    steps = recording.duration_s / step_s  # inf for a step of 5e-324 s
    count = math.floor(steps + 1e-9) + 1 if steps < MAX_STEPS else MAX_STEPS + 1
    if count > MAX_STEPS:
        expected = f"at most {MAX_STEPS} frames: a longer step (the recording is "
        expected += f"{recording.duration_s:g} s)"
        raise ProblemError(recording.source, "--resample", step_s, expected)
    if count < 2:
        expected = f"a step shorter than the recording ({recording.duration_s:g} s)"
        raise ProblemError(recording.source, "--resample", step_s, expected)
    time = recording.time[0] + step_s * np.arange(count)
    q = np.column_stack([np.interp(time, recording.time, col) for col in recording.q.T])
    held = recording.held
    if held is not None:
        before = np.searchsorted(recording.time, time + 1e-9, side="right") - 1
        held = held[before]
    residuals = _each(recording.residuals, lambda r: np.interp(time, recording.time, r))
    note = f"resampled to {step_s:g} s steps: {count} frames from {recording.frames}"
    return replace(
        recording, time=time, q=q, held=held, residuals=residuals, notes=(*recording.notes, note)
    )


def _each(
    residuals: dict[str, np.ndarray] | None, change: Callable[[np.ndarray], np.ndarray]
) -> dict[str, np.ndarray] | None:
    """A marker fit's residuals, each landmark's changed alike (None stays None)."""
    return None if residuals is None else {k: change(v) for k, v in residuals.items()}


def repeat(
    recording: Recording, *, times: int | None = None, until_s: float | None = None
) -> Recording:
    """The recording played ``times`` times in a row, or as often as it takes to reach
    ``until_s`` [s] after its first frame (the last cycle cut there): a work cycle. Each
    cycle starts one frame step (the recording's median) after the last one ends, from the
    recording's first posture."""
    if (times is None) == (until_s is None):
        raise ProblemError(None, "--repeat/--until", None, "one of the two")
    period = recording.duration_s + float(np.median(np.diff(recording.time)))
    if until_s is not None:
        if not (math.isfinite(until_s) and 0 < until_s <= MAX_DURATION_S):
            raise ProblemError(None, "--until", until_s, f"a time in s in (0, {MAX_DURATION_S:g}]")
        times = max(1, math.ceil((until_s + 1e-9) / period))
    assert times is not None
    most = MAX_STEPS // recording.frames
    if times > most and until_s is not None:
        expected = (
            f"at most {most * period:g} s: {MAX_STEPS} frames ({most} cycles of "
            f"{recording.frames}); resample to a longer step (--resample)"
        )
        raise ProblemError(None, "--until", until_s, expected)
    if times < 1 or times > most:
        expected = f"1 to {most} repetitions of {recording.frames} frames (--resample for more)"
        raise ProblemError(None, "--repeat", times, expected)
    offsets = period * np.arange(times)
    time = (recording.time[None, :] + offsets[:, None]).ravel()
    q = np.tile(recording.q, (times, 1))
    held = None if recording.held is None else np.tile(recording.held, (times, 1))
    residuals = _each(recording.residuals, lambda r: np.tile(r, times))
    if until_s is not None:
        keep = time - recording.time[0] <= until_s + 1e-9
        time, q = time[keep], q[keep]
        held = None if held is None else held[keep]
        residuals = _each(residuals, lambda r: r[keep])
    jump = float(np.degrees(np.abs(recording.q[-1] - recording.q[0]).max()))
    note = (
        f"repeated as a work cycle of {period:g} s: {times} cycles, {time.size} frames; "
        f"each cycle jumps back to the first frame's posture (largest change {jump:.1f}°)"
    )
    return replace(
        recording, time=time, q=q, held=held, residuals=residuals, notes=(*recording.notes, note)
    )


def held_frames(
    time: np.ndarray, windows: dict[str, list[list[float]]], loads: list[str], problem: Path
) -> np.ndarray | None:
    """Per frame at ``time`` [s], 1 for each of ``loads`` (names, in the problem's order)
    held then, 0 if not: a load named in ``windows`` is held within its [start, end] [s]
    intervals only, any other throughout; None when ``windows`` is empty (all held)."""
    if not windows:
        return None
    held = np.ones((time.size, len(loads)))
    for name, intervals in windows.items():
        if name not in loads:
            raise ProblemError(problem, f"motion.held_s.{name}", name, f"one of the loads {loads}")
        inside = np.zeros(time.size, dtype=bool)
        for start, end in intervals:
            inside |= (time >= start - 1e-9) & (time <= end + 1e-9)
        held[:, loads.index(name)] = inside
    return held


def fill_gaps(
    values: np.ndarray, time: np.ndarray, max_gap_s: float
) -> tuple[np.ndarray, list[tuple[int, int]], list[tuple[int, int]]]:
    """One DOF's values with its NaN runs filled: linearly between the frames around a run,
    with the nearest frame's value at either end. Returns the filled values and the runs
    (first and last frame index) no longer than ``max_gap_s`` [s] and those longer (measured
    from the last frame before the run to the first after, or the run's own span at an
    end). All NaN: nothing can be filled (ValueError)."""
    missing = np.isnan(values)
    if not missing.any():
        return values, [], []
    if missing.all():
        raise ValueError("no value at all")
    known = np.flatnonzero(~missing)
    filled = values.copy()
    filled[missing] = np.interp(time[missing], time[known], values[known])
    short, long = [], []
    edges = np.diff(np.concatenate(([0], missing.astype(int), [0])))
    for first, end in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
        last = end - 1
        before = time[first - 1] if first > 0 else time[first]
        after = time[end] if end < time.size else time[last]
        (short if after - before <= max_gap_s + 1e-12 else long).append((int(first), int(last)))
    return filled, short, long
