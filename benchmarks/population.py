"""Throughput of a population run on one and on two worker processes (not a test).

Run: python benchmarks/population.py [--n N] [--problem FILE] [--jobs J]

Draws N workers per sex (both sexes, seed 1) for the problem (default: the standing wall
hold, 29 DOF, the largest body with a population-ready task) and runs them as
``cp.population`` does, without files per worker: first in this process (one core), then on
J worker processes. Prints per run the wall time, the workers per minute, the seconds per
worker, the speed-up over one core, the time 1000 workers would take at that rate, and the
largest resident memory of the process that ran the workers (this one, then each worker
process, sampled with psutil, which the dask extra installs). Targets (issue 24): 1000
workers in at most 10 minutes on 2 cores, at least 1.8 times one core's throughput, at most
300 MB per worker. Measure them with ``--n 75`` (150 workers): with a few dozen, each
process's start (its imports and its one build, about 1.5 s) weighs on the speed-up.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import tempfile
import threading
import time
from pathlib import Path

import psutil

from casadi_posture import api
from casadi_posture.output.report import table

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


class PeakMemory:
    """The largest resident memory [MB] of this process (``own``) or of its worker processes,
    sampled every ``period_s`` while it runs (psutil; a worker's own size, not the parent's
    copy it was forked from)."""

    def __init__(self, own: bool, period_s: float = 0.2) -> None:
        self.own, self.period_s, self.peak_mb = own, period_s, 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._sample, daemon=True)

    def __enter__(self) -> PeakMemory:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()

    def _sample(self) -> None:
        me = psutil.Process()
        while not self._stop.wait(self.period_s):
            processes = [me] if self.own else me.children(recursive=True)
            for process in processes:
                with contextlib.suppress(psutil.Error):
                    self.peak_mb = max(self.peak_mb, process.memory_info().rss / 2**20)


def run(problem: Path, n: int, jobs: int) -> tuple[float, float]:
    """Wall time [s] of a population of ``n`` workers per sex on ``jobs`` processes, and the
    peak memory [MB] of the process that ran the workers."""
    with tempfile.TemporaryDirectory() as folder, PeakMemory(own=jobs == 1) as memory:
        start = time.perf_counter()
        report = api.population(problem, Path(folder) / "out", n=n, jobs=jobs, seed=1)
        elapsed = time.perf_counter() - start
    failed = sum(r.get("status") == "failed" for r in report.batch.rows)
    if failed:
        print(f"warning: {failed} workers failed", file=sys.stderr)
    return elapsed, memory.peak_mb


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=10, help="workers per sex (default 10)")
    parser.add_argument("--problem", type=Path, default=PROBLEMS / "standing_wall_horizontal.toml")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    args = parser.parse_args()
    workers = 2 * args.n
    rows = []
    one, own_mb = run(args.problem, args.n, 1)
    many, worker_mb = run(args.problem, args.n, args.jobs)
    for jobs, wall, memory in ((1, one, own_mb), (args.jobs, many, worker_mb)):
        rows.append(
            [
                jobs,
                workers,
                wall,
                60 * workers / wall,
                wall / workers,
                one / wall,
                1000 * wall / workers / 60,
                memory,
            ]
        )
    print(f"{args.problem.name}: {args.n} workers per sex, seed 1, no files per worker")
    print(
        table(
            [
                "processes",
                "workers",
                "wall (s)",
                "workers per min",
                "s per worker",
                "speed-up",
                "1000 workers (min)",
                "peak memory of a worker process (MB)",
            ],
            rows,
            digits=3,
        )
    )


if __name__ == "__main__":
    main()
