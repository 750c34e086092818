"""Fuzzing of recordings (see ``recording_fuzzing.py``): the shipped C3D file, a joint-angle
CSV of its angles and a BVH file of a known motion, mutated by a seeded generator;
``evaluate`` on each answers, flags or refuses in one line naming the file, never hangs.

CI runs ``FUZZ_RECORDINGS`` cases of each kind with a fixed seed."""

from __future__ import annotations

import os
import random
import time
from pathlib import Path

import numpy as np
import pytest
from bvh_files import bvh_problem, bvh_problem_file, write_bvh
from recording_fuzzing import (
    BOX,
    evaluate,
    invoke,
    mutate_c3d,
    mutate_text,
    problems,
    short_c3d,
)

import casadi_posture as cp
from casadi_posture import api
from casadi_posture.cli import motion, runs

FUZZ_RECORDINGS = int(os.environ.get("CASADI_POSTURE_FUZZ_RECORDINGS", "20"))
SEED = int(os.environ.get("CASADI_POSTURE_FUZZ_SEED", "38"))


@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, Path]]:
    """Each kind's problem file and unmutated recording: the shipped C3D file's first
    frames; the body's angles the IK finds in them, as a CSV file; a BVH file of 4 frames
    of the seated body's arms."""
    folder = tmp_path_factory.mktemp("recordings")
    c3d = short_c3d(folder / "box.c3d")
    recording = api.read_motion(cp.load(BOX), c3d)  # compiles the IK the children reuse
    names = [f"{d}_deg" for d in cp.load(BOX).body.dof_names]
    rows = np.column_stack([recording.time, np.degrees(recording.q)])
    csv = folder / "box.csv"
    np.savetxt(csv, rows, delimiter=",", header=",".join(["time_s", *names]), comments="")
    seated = bvh_problem()
    body = seated.body
    q = np.tile([0.5 * (d.lower + d.upper) for d in body.dofs], (4, 1))
    q[:, body.index["elbow_flexion_r"]] = np.radians([20.0, 40.0, 60.0, 80.0])
    bvh = write_bvh(folder / "arms.bvh", seated, q, frame_time=0.5)
    return {
        "c3d": (BOX, c3d),
        "csv": (BOX, csv),
        "bvh": (bvh_problem_file(folder / "seated.toml"), bvh),
    }


@pytest.mark.parametrize("kind", ["c3d", "csv", "bvh"])
def test_mutated_recordings_are_answered_flagged_or_refused_in_one_line(
    kind: str,
    recordings: dict[str, tuple[Path, Path]],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Every mutated recording: exit 0, 1 or 2 within the time limit, no internal error, a
    refusal in one line naming the file. The figures, 5 s a case and drawn from the same
    tables, are left out (tests/test_marker_ik.py, test_bvh.py and test_motion.py draw
    them); everything else evaluate writes and prints is done."""
    monkeypatch.setattr(motion, "write_run", _without_figures)
    problem, source = recordings[kind]
    original = source.read_bytes()
    rng = random.Random(f"{SEED}-{kind}")
    failures, codes = [], []
    start = time.monotonic()
    for case in range(FUZZ_RECORDINGS):
        path = tmp_path / f"{case}{source.suffix}"
        if kind == "c3d":
            data, how = mutate_c3d(original, tmp_path, rng)
        else:
            text, how = mutate_text(original.decode(), rng)
            data = text.encode()
        path.write_bytes(data)
        invoked = invoke(evaluate(problem, path, tmp_path / "out"))
        codes.append(invoked.exit_code)
        failures += [f"{path.name} ({how}): {p}" for p in problems(invoked, path)]
    seconds = time.monotonic() - start
    counts = {c: codes.count(c) for c in sorted(set(codes), key=str)}
    print(f"{kind}: {FUZZ_RECORDINGS} cases in {seconds:.1f} s, exit codes {counts}")
    assert not failures, "\n".join(failures)


def _without_figures(*args, **kwargs):
    return runs.write_run(*args, **kwargs, figures=False)


def test_the_unmutated_recordings_are_answered(
    recordings: dict[str, tuple[Path, Path]], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The fuzz's starting points are good recordings: each evaluated with exit 0 or 1."""
    monkeypatch.setattr(motion, "write_run", _without_figures)
    for kind, (problem, source) in recordings.items():
        invoked = invoke(evaluate(problem, source, tmp_path / kind))
        assert invoked.exit_code in (0, 1), (kind, invoked.stderr)
        assert not problems(invoked, source)
