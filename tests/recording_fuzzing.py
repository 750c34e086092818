"""Recordings made defective, and what ``evaluate`` must do with them.

Shared by the recordings' tests and their fuzz test (tests/test_fuzz_recordings.py): the
shipped C3D file (cut to its first frames, the calibration window and a little more), a
joint-angle CSV of the body's angles in them, and a BVH file of a known motion, each
mutated: cut at a random byte, values replaced by NaN, infinities, huge numbers or text,
lines or markers dropped, a marker's label repeated. Whatever the file, ``evaluate`` must:

- exit with code 0, 1 or 2, within ``TIME_LIMIT_S`` (run in a forked process, killed then);
- print no traceback and no "internal error";
- on exit 2, say what is wrong in one line naming the recording.
"""

from __future__ import annotations

import math
import multiprocessing
import random
import re
import struct
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import ezc3d
import numpy as np
from click.testing import CliRunner

from casadi_posture.cli import main

ROOT = Path(__file__).resolve().parents[1]
BOX = ROOT / "problems" / "recorded_box_transfer.toml"
BOX_C3D = ROOT / "problems" / "recordings" / "box_transfer.c3d"
#: Frames kept of the shipped C3D file: its calibration window (0-0.4 s at 50 Hz) and more.
FRAMES = 30
#: Longest a case may run [s]: a fuzzed recording is read and evaluated in about 1 s.
TIME_LIMIT_S = 30.0
#: What a value in a text file may be replaced by.
WEIRD = ["nan", "inf", "-inf", "1e308", "-1e308", "1e-320", "x", "", "1e999", "0", "-0"]
#: What a float of a C3D file's data may be replaced by.
WEIRD_FLOATS = [math.nan, math.inf, -math.inf, 3e38, -3e38, 1e20, 0.0]


@dataclass(frozen=True)
class Invoked:
    """A command's exit code (None: killed after ``TIME_LIMIT_S``), output and time [s]."""

    exit_code: int | None
    stdout: str
    stderr: str
    seconds: float


def invoke(args: list[str], limit_s: float = TIME_LIMIT_S) -> Invoked:
    """``casadi-posture args`` in a forked process (the parent's compiled solvers kept),
    killed after ``limit_s`` [s]."""
    context = multiprocessing.get_context("fork")
    receive, send = context.Pipe(duplex=False)
    process = context.Process(target=_invoke, args=(args, send))
    start = time.monotonic()
    process.start()
    send.close()
    done = receive.poll(limit_s)
    exit_code, stdout, stderr = receive.recv() if done else (None, "", "")
    process.kill()
    process.join()
    return Invoked(exit_code, stdout, stderr, time.monotonic() - start)


def _invoke(args: list[str], send) -> None:
    result = CliRunner().invoke(main, args)
    stderr = result.stderr
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        stderr += f"\nTraceback: raised {type(result.exception).__name__}: {result.exception}"
    send.send((result.exit_code, result.stdout, stderr))


def problems(invoked: Invoked, recording: Path) -> list[str]:
    """The rules above that ``invoked``, run on ``recording``, breaks."""
    out = []
    if invoked.exit_code is None:
        return [f"no answer in {TIME_LIMIT_S:g} s"]
    if invoked.exit_code not in (0, 1, 2):
        out.append(f"exit code {invoked.exit_code}")
    text = invoked.stdout + invoked.stderr
    if "Traceback" in text or "internal error" in text:
        out.append(f"a traceback or an internal error: {invoked.stderr.strip()[-300:]}")
    if invoked.exit_code == 2:
        lines = invoked.stderr.strip().splitlines()
        if len(lines) != 1:
            out.append(f"exit 2 with {len(lines)} lines on stderr")
        elif str(recording) not in lines[0]:
            out.append(f"exit 2 without naming the recording: {lines[0]}")
    return out


def evaluate(problem: Path, recording: Path, out: Path) -> list[str]:
    """The arguments of ``evaluate`` on ``recording`` with ``problem``, into ``out``."""
    return ["evaluate", str(problem), "--motion", str(recording), "--out", str(out), "--force"]


def short_c3d(path: Path, change: Callable[[list[str], np.ndarray], None] | None = None) -> Path:
    """The shipped C3D file's first ``FRAMES`` frames written to ``path`` as they are, or
    after ``change`` (labels, points (4, markers, frames) in mm) changed them in place."""
    source = ezc3d.c3d(str(BOX_C3D))
    labels = list(source["parameters"]["POINT"]["LABELS"]["value"])
    points = np.array(source["data"]["points"][:, :, :FRAMES])
    if change is not None:
        change(labels, points)
    target = ezc3d.c3d()
    target["parameters"]["POINT"]["RATE"]["value"] = [50.0]
    target["parameters"]["POINT"]["LABELS"]["value"] = labels
    target["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    target["data"]["points"] = points
    target.write(str(path))
    return path


def mutate_text(text: str, rng: random.Random) -> tuple[str, str]:
    """``text`` (a CSV or BVH file) mutated once, and how."""
    lines = text.splitlines()
    kind = rng.choice(["cut", "value", "values", "drop", "repeat"])
    if kind == "cut":
        at = rng.randrange(len(text))
        return text[:at], f"cut at byte {at}"
    if kind in ("value", "values"):
        numbers = list(re.finditer(r"-?[0-9][0-9.eE+-]*", text))
        out, how = text, []
        for match in sorted(
            rng.sample(numbers, 1 if kind == "value" else 5), key=lambda m: -m.start()
        ):
            weird = rng.choice(WEIRD)
            out = out[: match.start()] + weird + out[match.end() :]
            how.append(f"{match.group()}→{weird!r} at byte {match.start()}")
        return out, "; ".join(how)
    k = rng.randrange(len(lines))
    if kind == "drop":
        return "\n".join(lines[:k] + lines[k + 1 :]) + "\n", f"line {k + 1} dropped"
    return "\n".join(lines[: k + 1] + lines[k:]) + "\n", f"line {k + 1} twice"


def mutate_c3d(data: bytes, folder: Path, rng: random.Random) -> tuple[bytes, str]:
    """A C3D file's bytes ``data`` mutated once, and how: cut, bytes or data floats
    overwritten, or (rewritten by ezc3d in ``folder``) a marker dropped, unseen or named as
    another."""
    kind = rng.choice(["cut", "bytes", "floats", "drop", "unseen", "rename"])
    if kind == "cut":
        at = rng.randrange(len(data))
        return data[:at], f"cut at byte {at}"
    if kind == "bytes":
        out = bytearray(data)
        at = sorted(rng.randrange(len(data)) for _ in range(rng.randint(1, 8)))
        for i in at:
            out[i] = rng.randrange(256)
        return bytes(out), f"bytes {at} overwritten"
    if kind == "floats":
        out, start = bytearray(data), 512 * (data[8 * 2] - 1)  # header word 9: data's block
        at = sorted(rng.randrange(start // 4, len(data) // 4) * 4 for _ in range(rng.randint(1, 4)))
        value = rng.choice(WEIRD_FLOATS)
        for i in at:
            out[i : i + 4] = struct.pack("<f", value)
        return bytes(out), f"floats at bytes {at} set to {value}"
    label = rng.choice(MAPPED)

    def change(labels: list[str], points: np.ndarray) -> None:
        j = labels.index(label)
        if kind == "drop":
            labels[j] = f"{label}_gone"
        elif kind == "unseen":
            points[:3, j] = np.nan
        else:
            labels[j] = rng.choice([other for other in labels if other != label])

    path = short_c3d(folder / "changed.c3d", change)
    return path.read_bytes(), f"marker {label}: {kind}"


#: The labels recorded_box_transfer.toml maps.
MAPPED = [
    *("ASISr", "ASISl", "PSISr", "PSISl", "STER", "XIPH", "T1", "T10", "EPICl", "EPICm"),
    *("STYLr", "STYLu", "INDEX", "LASTC", "ACRO_tip", "SCAP_AA", "CLAV_AC"),
]
