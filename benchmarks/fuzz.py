"""A fuzz campaign over mutated problem files and command lines (not a test).

Run: python benchmarks/fuzz.py [--examples N] [--seed S]

Each example is a shipped problem file with one to three mutations and one command line
(``tests/fuzzing.py`` says which, and the rules every command must keep). Prints the
number of files tried, the exit codes per command, the slowest run, and every broken
rule; exits with code 1 if any rule was broken.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections import Counter, defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from fuzzing import Case, Outcome, cases, run_case
from hypothesis import HealthCheck, given, seed, settings

from casadi_posture.output.report import table


def campaign(examples: int, chosen_seed: int) -> list[tuple[Case, Outcome]]:
    """Run ``examples`` fuzzed cases; every outcome, broken rules included."""
    seen: list[tuple[Case, Outcome]] = []

    @seed(chosen_seed)
    @settings(
        max_examples=examples,
        deadline=None,
        database=None,
        suppress_health_check=list(HealthCheck),
    )
    @given(cases())
    def one(case: Case) -> None:
        with tempfile.TemporaryDirectory() as folder:
            seen.append((case, run_case(case, Path(folder))))

    one()
    return seen


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--examples", type=int, default=500)
    parser.add_argument("--seed", type=int, default=2026)
    args = parser.parse_args()
    start = time.monotonic()
    seen = campaign(args.examples, args.seed)
    wall = time.monotonic() - start
    codes: dict[str, Counter] = defaultdict(Counter)
    slowest: dict[str, float] = defaultdict(float)
    for _, outcome in seen:
        codes[outcome.command][outcome.exit_code] += 1
        slowest[outcome.command] = max(slowest[outcome.command], outcome.seconds)
    rows = [
        [
            command,
            sum(codes[command].values()),
            codes[command][0],
            codes[command][1],
            codes[command][2],
            sum(n for code, n in codes[command].items() if code not in (0, 1, 2)),
            slowest[command],
        ]
        for command in sorted(codes)
    ]
    rows.append(
        [
            "all",
            len(seen),
            *(sum(codes[c][code] for c in codes) for code in (0, 1, 2)),
            sum(n for c in codes for code, n in codes[c].items() if code not in (0, 1, 2)),
            max(slowest.values(), default=0.0),
        ]
    )
    print(
        f"{len(seen)} fuzzed problem files and command lines (seed {args.seed}), "
        f"{wall:.0f} s wall\n"
    )
    print(
        table(
            ["command", "runs", "exit 0", "exit 1", "exit 2", "other", "slowest (s)"],
            rows,
            digits=2,
        )
    )
    broken = [(case, outcome) for case, outcome in seen if outcome.problems]
    print(f"\nbroken rules: {len(broken)}")
    for case, outcome in broken[:20]:
        print(f"  {case.source} {case.mutations} {case.command} {case.options}: {outcome.problems}")
    if broken:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
