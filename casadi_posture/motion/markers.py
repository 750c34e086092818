"""C3D marker recordings: the labelled points of a motion-capture file, in metres, read with
ezc3d (pip install 'casadi_posture[motion]')."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from casadi_posture.errors import MISSING, ProblemError
from casadi_posture.motion.recording import check_times

#: Metres per unit of POINT:UNITS.
UNITS_M = {"mm": 1e-3, "cm": 1e-2, "m": 1.0}
#: The second byte of every C3D file: its parameter section's key (C3D.org, header word 1).
C3D_KEY = 0x50


@dataclass(frozen=True)
class Markers:
    """Labelled markers of a C3D file: ``time`` [s] per frame, the first frame's number over
    the point rate; ``positions`` [m] (frames, markers, 3) in the lab frame, NaN where a
    marker was not seen; ``labels`` in the order of ``positions``' second axis."""

    source: Path
    time: np.ndarray
    labels: tuple[str, ...]
    positions: np.ndarray

    def marker(self, label: str) -> np.ndarray:
        """The positions [m] (frames, 3) of the marker ``label``."""
        return self.positions[:, self.labels.index(label)]


def read_c3d(path: str | Path) -> Markers:
    """The markers of the C3D file ``path``; a point with a negative residual or at exactly
    (0, 0, 0), ezc3d's and some writers' marks of a point not seen, is NaN. A file that is
    not C3D, has no points or has POINT:UNITS other than mm, cm or m is a one-line error."""
    path = Path(path)
    c3d = _open(path)
    header = c3d["header"]["points"]
    points = np.asarray(c3d["data"]["points"], dtype=float)
    if header["size"] < 1 or points.ndim != 3 or points.shape[2] < 1:
        raise ProblemError(path, "POINT", MISSING, "a C3D file with marker points (it has none)")
    group = c3d["parameters"]["POINT"]
    units = [str(u).strip().lower() for u in group.get("UNITS", {}).get("value", [])]
    if not units or units[0] not in UNITS_M:
        value = units[0] if units else MISSING
        raise ProblemError(path, "POINT:UNITS", value, f"one of {list(UNITS_M)}")
    labels = _labels(group, points.shape[1])
    residuals = np.asarray(c3d["data"]["meta_points"]["residuals"], dtype=float)
    xyz = points[:3].transpose(2, 1, 0)
    positions = xyz * UNITS_M[units[0]]
    positions[(residuals[0].T < 0) | np.all(xyz == 0.0, axis=2)] = np.nan
    rate = float(header["frame_rate"])
    if not rate > 0:
        raise ProblemError(path, "POINT:RATE", rate, "a point rate in Hz above 0")
    time = (header["first_frame"] + np.arange(positions.shape[0])) / rate
    check_times(time, path, "POINT:FRAMES")
    return Markers(path, time, labels, positions)


def _open(path: Path) -> dict:
    """The file read by ezc3d; ezc3d not installed, a missing file or one that is not C3D
    (checked before ezc3d parses it) is a one-line error."""
    try:
        import ezc3d
    except ImportError:
        expected = "ezc3d to read C3D files: pip install 'casadi_posture[motion]'"
        raise ProblemError(path, None, None, expected) from None
    try:
        with path.open("rb") as handle:
            start = handle.read(512)
    except OSError as error:
        raise ProblemError(path, None, None, f"a readable C3D file ({error.strerror})") from None
    if len(start) < 512 or start[1] != C3D_KEY:
        raise ProblemError(path, None, None, "a C3D file (this one is not: wrong header)")
    try:
        return ezc3d.c3d(str(path))
    except (OSError, RuntimeError, ValueError) as error:
        message = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise ProblemError(path, None, None, f"a readable C3D file ({message})") from None


def _labels(group: dict, count: int) -> tuple[str, ...]:
    """The first ``count`` point labels, from POINT:LABELS then LABELS2, LABELS3, ... (a
    file of more than 255 points); a point without one is named ``point<k>``, from 1."""
    labels: list[str] = []
    key, k = "LABELS", 1
    while key in group:
        labels += [str(label).strip() for label in group[key]["value"]]
        k += 1
        key = f"LABELS{k}"
    labels += [f"point{i + 1}" for i in range(len(labels), count)]
    return tuple(labels[:count])
