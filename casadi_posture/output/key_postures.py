"""The moments of a run its figures show: the recoveries and the key postures (initial,
each recovery, final), and the title every figure of the run carries."""

from __future__ import annotations

import textwrap

import numpy as np

from casadi_posture.output.time_axis import time_unit
from casadi_posture.simulation import SimulationResult

#: Recovery postures drawn in the posture figures (summary.json lists them all).
DRAWN_RECOVERIES = 5

#: A posture to draw: its step, its label and its colour.
Shown = tuple[int, str, object]


#: Characters of a figure title's line: a longer title wraps instead of being cut off.
TITLE_WIDTH = 70


def title(result: SimulationResult, width: int = TITLE_WIDTH) -> str:
    """Problem, strategy and solver (a replay: the recording), and whether the run was cut
    short, wrapped at ``width`` characters (the default fits a figure 8 inches wide at 12
    points)."""
    if result.recording is not None:
        text = f"{result.problem.path.stem}: recorded motion {result.recording.source.name}"
    else:
        text = f"{result.problem.path.stem}: {result.settings.describe()}, {result.solver}"
    if result.stop == "interrupted":
        text += " (interrupted: partial run)"
    elif result.stop == "never_held":
        text += " (task never held)"
    return textwrap.fill(text, width)


def recoveries(result: SimulationResult) -> list[int]:
    """Steps at which the constraint was released (recovery postures)."""
    tl = result.timeline
    return [
        int(np.argmax(tl.time >= e.time_s)) for e in result.events if e.kind == "constraint_off"
    ]


def key_postures(result: SimulationResult) -> list[Shown]:
    """The initial posture (black), the first few recovery postures (viridis), on a recorded
    motion the one of the largest load (purple), and the last (red), times in the run's
    unit (``time_unit``); postures within 0.5° of an earlier one merged into it (a cycle
    that recovers where it recovered before)."""
    tl = result.timeline
    _, unit = time_unit(tl.time)

    def when(step: int) -> str:
        return f"{tl.time[step] / 60:.1f} min" if unit == "min" else f"{tl.time[step]:g} s"

    steps = recoveries(result)
    shown: list[Shown] = [(0, "initial", "black")]
    drawn = steps[:DRAWN_RECOVERIES]
    from matplotlib import colormaps  # imported when drawn (casadi_posture.output)

    colours = colormaps["viridis"](np.linspace(0.15, 0.85, max(len(drawn), 1)))
    for step, colour in zip(drawn, colours, strict=False):
        shown.append((step, f"recovery at {when(step)}", colour))
    if len(steps) > DRAWN_RECOVERIES:
        step, label, colour = shown[-1]
        shown[-1] = (step, f"{label} (+{len(steps) - DRAWN_RECOVERIES} more)", colour)
    if result.recording is not None and np.isfinite(tl.load).any():
        step, group = np.unravel_index(np.nanargmax(tl.load), tl.load.shape)
        name = result.problem.body.half_joints[group].name
        label = f"largest load at {when(step)}: {name}, {tl.load[step, group]:.0f} %MVC"
        shown.append((int(step), label, "tab:purple"))
    last = tl.time.size - 1
    shown.append((last, f"end ({when(last)})", "tab:red"))
    return _merge_repeats(shown, tl.q)


def _merge_repeats(shown: list[Shown], q: np.ndarray, tolerance_deg: float = 0.5) -> list[Shown]:
    """One stick figure per distinct posture: postures within ``tolerance_deg`` of an earlier
    one add their label to it."""
    merged: list[Shown] = []
    for step, label, colour in shown:
        same = next(
            (
                k
                for k, (other, _, _) in enumerate(merged)
                if np.max(np.abs(np.degrees(q[step] - q[other]))) < tolerance_deg
            ),
            None,
        )
        if same is None:
            merged.append((step, label, colour))
        else:
            first, text, first_colour = merged[same]
            merged[same] = (first, f"{text}; {label}", first_colour)
    return merged
