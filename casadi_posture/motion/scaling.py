"""Segment lengths measured on the subject from a static trial (``motion.scale_segments``;
docs/motion.md): the distance between the markers of a segment's two end landmarks, as
OpenSim's scale tool takes a marker pair's distance, here straight as the length."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import casadi as ca
import numpy as np

from casadi_posture.body.tree import BodyModel
from casadi_posture.data.parameters import data_name
from casadi_posture.errors import ProblemError
from casadi_posture.motion.markers import Markers, check_labels

#: A measured length this many times the body's, or its inverse, is refused: the markers are
#: mapped to the wrong landmarks, or the file's units are not what it says.
MAX_LENGTH_RATIO = 2.0


def measured_lengths(
    markers: Markers,
    body: BodyModel,
    mapping: Mapping[str, Sequence[str]],
    segments: Sequence[str],
    window_s: Sequence[float] | None,
    problem: Path | None,
) -> dict[str, float]:
    """Each segment of ``segments`` (a model's segment name, ``forearm``: both sides) at the
    subject's length [m]: per side whose end landmarks (the body segment's proximal and
    distal) ``mapping`` maps, the distance between their markers' means, averaged over the
    frames of ``window_s`` ([start, end] [s], the static trial) where all are seen; the
    sides' mean. A segment without both ends mapped, a window without such a frame, or a
    length off the body's by more than ``MAX_LENGTH_RATIO`` is a one-line error."""
    key = "motion.scale_segments"
    if window_s is None:
        expected = "motion.calibrate_s too: the lengths are measured in that static window"
        raise ProblemError(problem, key, list(segments), expected)
    time = markers.time
    inside = (time >= window_s[0] - 1e-9) & (time <= window_s[1] + 1e-9)
    zero = _at_zero(body)
    out: dict[str, float] = {}
    for name in segments:
        sides = [s for s in body.segments if s.name in (name, f"{name}_r", f"{name}_l")]
        ends = [(s.proximal, s.distal) for s in sides if s.proximal and s.distal]
        mapped = [(a, b) for a, b in ends if a in mapping and b in mapping]
        if not ends:
            known = sorted({data_name(s.name) for s in body.segments if s.proximal and s.distal})
            expected = f"a segment of the body with two end landmarks: {', '.join(known)}"
            raise ProblemError(problem, key, name, expected)
        if not mapped:
            wanted = " or ".join(f"{a} and {b}" for a, b in ends)
            expected = f"a segment whose end landmarks are mapped in motion.markers ({wanted})"
            raise ProblemError(problem, key, name, expected)
        check_labels(
            markers, {n: mapping[n] for pair in mapped for n in pair}, "motion.markers", problem
        )
        lengths = []
        for a, b in mapped:
            first, second = (_mean(markers, mapping[n]) for n in (a, b))
            seen = inside & np.isfinite(first).all(axis=1) & np.isfinite(second).all(axis=1)
            if not seen.any():
                expected = (
                    f"frames of motion.calibrate_s where the markers of {a} and {b} are seen "
                    f"in {markers.source}"
                )
                raise ProblemError(problem, key, name, expected)
            length = float(np.linalg.norm(second[seen] - first[seen], axis=1).mean())
            model = float(np.linalg.norm(zero[b] - zero[a]))
            if not 1 / MAX_LENGTH_RATIO <= length / model <= MAX_LENGTH_RATIO:
                expected = (
                    f"a length from {a} to {b} within {MAX_LENGTH_RATIO:g}× the body's "
                    f"{model:.3f} m (measured {length:.3f} m: markers mapped to other "
                    "landmarks, or other units?)"
                )
                raise ProblemError(problem, key, name, expected)
            lengths.append(length)
        length = float(np.mean(lengths))
        out[name] = length
    return out


def lengths_note(lengths: Mapping[str, float], before: Mapping[str, float]) -> str:
    """The note a scaled recording carries: each segment's length [m] before and after."""
    changes = ", ".join(f"{n} {before[n]:.3f} → {v:.3f} m" for n, v in lengths.items())
    return f"segments scaled to the subject in the static window: {changes}"


def body_lengths(body: BodyModel, segments: Sequence[str]) -> dict[str, float]:
    """Each named segment's length in ``body`` [m], the mean of its sides' end landmarks'
    distance at the zero posture (segments ``measured_lengths`` accepted)."""
    zero, out = _at_zero(body), {}
    for name in segments:
        ends = [
            (s.proximal, s.distal)
            for s in body.segments
            if s.name in (name, f"{name}_r", f"{name}_l") and s.proximal and s.distal
        ]
        out[name] = float(np.mean([np.linalg.norm(zero[b] - zero[a]) for a, b in ends]))
    return out


def _mean(markers: Markers, labels: Sequence[str]) -> np.ndarray:
    """The mean of the markers ``labels`` per frame [m] (NaN where one is not seen)."""
    return np.mean([markers.marker(label) for label in labels], axis=0)


def _at_zero(body: BodyModel) -> dict[str, np.ndarray]:
    """Every landmark of ``body`` at the zero posture [m], in one compiled call."""
    names = list(body.landmarks)
    where = ca.Function("where", [body.q], [ca.horzcat(*[body.landmark(n) for n in names])])
    return dict(zip(names, np.asarray(where(np.zeros(body.n))).T, strict=True))
