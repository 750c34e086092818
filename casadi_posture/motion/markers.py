"""C3D marker recordings: the labelled points of a motion-capture file, in metres, read with
ezc3d (pip install 'casadi_posture[motion]')."""

from __future__ import annotations

import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from casadi_posture.errors import MISSING, ProblemError
from casadi_posture.motion.angles import closest
from casadi_posture.motion.recording import check_times

#: Metres per unit of POINT:UNITS.
UNITS_M = {"mm": 1e-3, "cm": 1e-2, "m": 1.0}
#: The second byte of every C3D file: its parameter section's key (C3D.org, header word 1).
C3D_KEY = 0x50
#: The processor type (the parameter section's 4th byte) of a big-endian file (MIPS).
BIG_ENDIAN = 86
#: A marker farther than this from the lab's origin [m] is not in any lab.
MAX_LAB_M = 100.0
#: At most this many of a file's labels are listed when a mapped one is not there.
MAX_LISTED = 60


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
        """The positions [m] (frames, 3) of the marker ``label`` (in the file once:
        ``check_labels``); a coordinate that is infinite or farther than ``MAX_LAB_M`` from
        the lab's origin is a one-line error naming the label and the frame."""
        xyz = self.positions[:, self.labels.index(label)]
        far = np.argwhere(np.abs(xyz) > MAX_LAB_M)
        if far.size:
            k, axis = (int(i) for i in far[0])
            key = f"{label} (frame {k + 1}, {'xyz'[axis]} in m)"
            expected = f"a coordinate within {MAX_LAB_M:g} m of the lab's origin (POINT:UNITS?)"
            raise ProblemError(self.source, key, float(xyz[k, axis]), expected)
        return xyz


def check_labels(
    markers: Markers, mapping: Mapping[str, Sequence[str]], key: str, problem: Path | None
) -> None:
    """Every label of ``mapping`` (a name → labels table of the problem file ``problem``,
    under ``key``) found once in the marker file; one that is not is a one-line error naming
    its key and the labels there are."""
    for name, labels in mapping.items():
        for label in labels:
            count = markers.labels.count(label)
            if count == 0:
                expected = f"a marker label of {markers.source} ({_choices(label, markers)})"
                raise ProblemError(problem, f"{key}.{name}", label, expected)
            if count > 1:
                expected = f"a label found once in {markers.source} (it is there {count} times)"
                raise ProblemError(problem, f"{key}.{name}", label, expected)


def _choices(label: str, markers: Markers) -> str:
    """'did you mean' words for ``label``, or else the file's labels in alphabetical order
    (the first ``MAX_LISTED``)."""
    close = closest(label, list(markers.labels))
    if close.startswith("did you mean"):
        return close
    labels = sorted(markers.labels, key=str.lower)
    more = f" and {len(labels) - MAX_LISTED} more" if len(labels) > MAX_LISTED else ""
    return f"its {len(labels)} labels: {', '.join(labels[:MAX_LISTED])}{more}"


def read_c3d(path: str | Path) -> Markers:
    """The markers of the C3D file ``path``; a point with a negative residual or at exactly
    (0, 0, 0), ezc3d's and some writers' marks of a point not seen, is NaN. A file that is
    not C3D, has no points, fewer frames than its header declares (cut short) or POINT:UNITS
    other than mm, cm or m is a one-line error."""
    path = Path(path)
    c3d, declared = _open(path)
    header = c3d["header"]["points"]
    points = np.asarray(c3d["data"]["points"], dtype=float)
    if header["size"] < 1 or points.ndim != 3 or points.shape[2] < 1:
        raise ProblemError(path, "POINT", MISSING, "a C3D file with marker points (it has none)")
    if declared is not None and points.shape[2] < declared:
        expected = f"the {declared} frames its header declares: the file is cut short"
        raise ProblemError(path, "frames", points.shape[2], expected)
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


def _open(path: Path) -> tuple[dict, int | None]:
    """The file read by ezc3d, and the number of frames its header declares (``_declared``:
    ezc3d reads a file cut short without a word); ezc3d not installed, a missing file or one
    that is not C3D (checked before ezc3d parses it) is a one-line error."""
    try:
        import ezc3d
    except ImportError:
        expected = "ezc3d to read C3D files: pip install 'casadi_posture[motion]'"
        raise ProblemError(path, None, None, expected) from None
    try:
        with path.open("rb") as handle:
            start = handle.read(512)
            block = start[0] if start else 1  # the parameter section's, from 1
            handle.seek(512 * max(block - 1, 0) + 3)
            processor = handle.read(1)
    except OSError as error:
        raise ProblemError(path, None, None, f"a readable C3D file ({error.strerror})") from None
    if len(start) < 512 or start[1] != C3D_KEY or not processor:
        raise ProblemError(path, None, None, "a C3D file (this one is not: wrong header)")
    try:
        return ezc3d.c3d(str(path)), _declared(start, processor[0])
    except (OSError, RuntimeError, ValueError) as error:
        message = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise ProblemError(path, None, None, f"a readable C3D file ({message})") from None


def _declared(header: bytes, processor: int) -> int | None:
    """The number of frames a C3D header declares (words 4 and 5: the first and last frame),
    in the byte order of the file's ``processor``; None when the header cannot say (65535
    frames or more, or a last frame before the first)."""
    first, last = struct.unpack(">HH" if processor == BIG_ENDIAN else "<HH", header[6:10])
    return last - first + 1 if first <= last < 0xFFFF else None


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
