"""Speed and accuracy of marker IK (C3D markers to joint angles) on the two shipped bodies,
with each IK solver (not a test).

Run: python benchmarks/marker_ik.py [--frames N] [--noise-mm S]

Per body (upper body, 17 DOF; standing, 29 DOF) a smooth motion of N frames at 100 Hz
(every DOF swings ±10° around a quarter of its range, one period over the recording),
every landmark one marker, seen from a lab turned 150° and
shifted 1.1 m, with Gaussian noise of S mm per coordinate (seeded). Per solver: the wall
time per frame (after a run that builds the solver), the median and largest landmark
residual [mm], the largest angle error [deg] against the known motion and the flags.
The angle error leaves out the forearms and wrists: a hand's landmarks (wrist, grip,
knuckles) lie on one line, so its turn about it is not measured (the posture level sets it).
Then the shipped recording (problems/recordings/box_transfer.c3d, 290 frames: clusters,
a calibration, fitted as segments) read by each solver, the C3D file and the calibration
included in the time.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import casadi as ca
import numpy as np

from casadi_posture.api import read_motion
from casadi_posture.ik.solvers import SOLVER_NAMES
from casadi_posture.ik.tasks import rotation_rpy
from casadi_posture.motion.marker_ik import markers_to_recording
from casadi_posture.motion.markers import Markers
from casadi_posture.output.report import table
from casadi_posture.problem import Problem, load_problem

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
BODIES = {"upper body": "seated_assembly.toml", "standing": "standing_wall_horizontal.toml"}
RECORDED = ("recorded_box_transfer.toml", "recordings/box_transfer.c3d")
RATE_HZ = 100.0
#: The lab frame: body = R · lab + t.
R_LAB = rotation_rpy(0.05, -0.1, np.radians(150.0))
T_LAB = np.array([1.0, 0.5, 0.0])


def motion(problem: Problem, frames: int) -> np.ndarray:
    """Postures [rad] (frames, DOFs): each DOF ±10° around a quarter of its range from its
    lower limit, phases spread over the DOFs."""
    body = problem.body
    centre = body.lower + 0.25 * (body.upper - body.lower)
    phase = 2 * np.pi * np.arange(frames)[:, None] / frames + np.arange(body.n)[None, :]
    return centre + np.radians(10.0) * np.sin(phase)


def lab_markers(problem: Problem, q: np.ndarray, noise_m: float, seed: int = 1) -> Markers:
    """One marker per landmark, named after it, in the lab [m] at postures ``q``."""
    body = problem.body
    names = list(body.landmarks)
    at = ca.Function("at", [body.q], [ca.horzcat(*[body.landmark(n) for n in names]).T])
    points = np.array([(np.asarray(at(qk)) - T_LAB) @ R_LAB for qk in q])
    points += np.random.default_rng(seed).normal(0.0, noise_m, points.shape)
    time_s = np.arange(q.shape[0]) / RATE_HZ
    return Markers(Path("synthetic.c3d"), time_s, tuple(n.upper() for n in names), points)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=100)
    parser.add_argument("--noise-mm", type=float, default=1.0)
    args = parser.parse_args()
    rows = []
    for label, file in BODIES.items():
        problem = load_problem(PROBLEMS / file)
        q = motion(problem, args.frames)
        markers = lab_markers(problem, q, args.noise_mm * 1e-3)
        mapping = {n: [n.upper()] for n in problem.body.landmarks}
        names = problem.body.dof_names
        arm = [i for i, d in enumerate(names) if not d.startswith(("forearm_", "wrist_"))]
        for solver in SOLVER_NAMES:
            run = (markers, problem.body, mapping, problem.posture, solver)
            markers_to_recording(*run)
            start = time.perf_counter()
            recording, fit = markers_to_recording(*run)
            per_frame = (time.perf_counter() - start) / args.frames
            rows.append(
                [
                    label,
                    problem.body.n,
                    solver,
                    1e3 * per_frame,
                    1e3 * float(np.median(fit.residuals)),
                    1e3 * float(fit.residuals.max()),
                    float(np.degrees(np.abs(recording.q - q)[:, arm].max())),
                    len(recording.flags),
                ]
            )
    print(f"{args.frames} frames, {args.noise_mm:g} mm marker noise\n")
    headers = [
        "body",
        "DOF",
        "solver",
        "ms/frame",
        "median residual mm",
        "max residual mm",
        "max angle error deg (no hands)",
        "flags",
    ]
    print(table(headers, rows, digits=3))
    problem = load_problem(PROBLEMS / RECORDED[0])
    recorded = []
    for solver in SOLVER_NAMES:
        read_motion(problem, PROBLEMS / RECORDED[1], solver=solver)
        start = time.perf_counter()
        recording = read_motion(problem, PROBLEMS / RECORDED[1], solver=solver)
        seconds = time.perf_counter() - start
        worst = {k: float(v.max()) for k, v in (recording.residuals or {}).items()}
        recorded.append([solver, recording.frames, 1e3 * seconds / recording.frames,
                         1e3 * max(v for k, v in worst.items() if k != "shoulder_r"),
                         1e3 * worst["shoulder_r"]])  # fmt: skip
    print(f"\nthe shipped recording ({RECORDED[1]}, upper body)\n")
    headers = ["solver", "frames", "ms/frame", "max residual mm (not shoulder)", "shoulder mm"]
    print(table(headers, recorded, digits=3))


if __name__ == "__main__":
    main()
