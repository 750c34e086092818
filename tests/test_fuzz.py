"""Property-based fuzzing of problem files and command lines (see ``fuzzing.py``).

CI runs a fixed seed and ``FUZZ_EXAMPLES`` examples; ``benchmarks/fuzz.py`` runs a larger
campaign and prints the outcomes per command.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from fuzzing import Case, cases, run_case
from hypothesis import HealthCheck, given, settings

FUZZ_EXAMPLES = int(os.environ.get("CASADI_POSTURE_FUZZ_EXAMPLES", "150"))


@settings(
    max_examples=FUZZ_EXAMPLES,
    derandomize=True,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(cases())
def test_every_command_answers_or_refuses_cleanly(case: Case) -> None:
    with tempfile.TemporaryDirectory() as folder:
        outcome = run_case(case, Path(folder))
    assert not outcome.problems, (case.source, case.mutations, case.command, case.options)
