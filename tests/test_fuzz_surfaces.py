"""Property-based fuzzing of the surfaces around a run (issue 38 item 7): output paths the
file system refuses, hand-edited manifests for rerun, --set values, what-if values, loads
far past strength, and body-tree region names. Seeded (derandomized), about 40 s on a busy
core; ``CASADI_POSTURE_FUZZ_EXAMPLES`` scales the examples.

Whatever the input, a command exits 0, 1 or 2, never prints a traceback or an internal
error, and refuses (exit 2) in one line that names what it refuses: the output option and
the path, the manifest and its key, the problem file.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner, Result
from conftest import PROBLEMS
from fuzzing import Case, cases, run_case
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from casadi_posture.body.tree import REGIONS
from casadi_posture.cli import main
from casadi_posture.data.templates import template

SCALE = int(os.environ.get("CASADI_POSTURE_FUZZ_EXAMPLES", "150")) / 150
HOLD = str(PROBLEMS / "holding_m45.toml")
QUICK = ["--duration", "5", "--no-figures", "--no-report"]


def fuzzed(examples: int) -> Callable:
    """Hypothesis settings: ``examples`` (scaled), derandomized, no deadline."""
    return settings(
        max_examples=max(1, round(examples * SCALE)),
        derandomize=True,
        deadline=None,
        database=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )


def check(result: Result, *named: str) -> list[str]:
    """The rules every command keeps; on exit 2 the one line must name each of ``named``.
    The stderr lines."""
    text = result.output + result.stderr
    assert result.exit_code in (0, 1, 2), (result.exit_code, text[-500:])
    assert "Traceback" not in text and "internal error" not in text, text[-500:]
    lines = result.stderr.strip().split("\n")  # a terminal's lines (not str.splitlines')
    if result.exit_code == 2:
        assert len(lines) == 1 and lines[0].startswith("error: "), lines
        for name in named:
            assert name in lines[0], (name, lines[0])
    return lines


# --- output paths ----------------------------------------------------------------------

#: Commands with their output (OUT); the cheap ones also run when the path is good.
WRITERS: dict[str, tuple[list[str], str, bool]] = {
    "simulate": (["simulate", HOLD, *QUICK, "--out", "OUT"], "", True),
    "solve": (["solve", HOLD, "--out", "OUT"], "", True),
    "curve": (["curve", HOLD, "--dof", "elbow_flexion", "--out", "OUT"], ".png", True),
    "init": (["init", "hold", "OUT"], ".toml", True),
    "whatif": (
        ["whatif", HOLD, "--static", "--quiet", "--vary", "title=a", "--out", "OUT"],
        "",
        True,
    ),
    "batch": (["batch", HOLD, "--quiet", "--out", "OUT"], "", False),
    "population": (["population", HOLD, "--n", "1", "--out", "OUT"], "", False),
    "duty-cycle": (["duty-cycle", HOLD, "--t-off", "30", "--out", "OUT"], "", False),
    "sensitivity": (["sensitivity", HOLD, "--out", "OUT"], "", False),
    "compare": (["compare", HOLD, "--out", "OUT"], "", False),
}
REFUSED = ["file parent", "long name", "dangling", "loop", "through loop", "proc", "sys"]
GOOD = ["new nested", "empty folder"]


def _out_path(kind: str, folder: Path, suffix: str, length: int, letter: str) -> Path:
    """An output of ``kind`` under ``folder`` (names ending in ``suffix``), its parts made."""
    if kind == "file parent":
        (folder / "afile").write_text("")
        return folder / "afile" / f"out{suffix}"
    if kind == "long name":
        return folder / (letter * length + suffix)
    if kind == "dangling":
        (folder / f"link{suffix}").symlink_to(f"nowhere{suffix}")
        return folder / f"link{suffix}"
    if kind in ("loop", "through loop"):
        (folder / f"loop{suffix}").symlink_to(f"loop{suffix}")
        return folder / f"loop{suffix}" / ("out" if kind == "through loop" else "")
    if kind in ("proc", "sys"):
        return Path(f"/{kind}") / f"casadi-posture-out{suffix}"
    if kind == "empty folder":
        (folder / "empty").mkdir()
        return folder / "empty"
    return folder / f"new{suffix}" if suffix else folder / "new" / "deeper"


@fuzzed(80)
@given(
    command=st.sampled_from(sorted(WRITERS)),
    kind=st.sampled_from(REFUSED + GOOD),
    length=st.integers(256, 1000),
    letter=st.sampled_from(["x", "é", "数"]),
    force=st.booleans(),
)
def test_an_output_the_file_system_refuses_is_one_line(
    command: str, kind: str, length: int, letter: str, force: bool
) -> None:
    args, suffix, cheap = WRITERS[command]
    if (kind in GOOD and not cheap) or (kind in ("proc", "sys") and not Path(f"/{kind}").is_dir()):
        return
    if kind in GOOD and suffix:
        kind = "new nested"  # a file's output is never an existing folder
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        out = _out_path(kind, folder, suffix, length, letter)
        given = [a.replace("OUT", str(out)) for a in args] + (["--force"] if force else [])
        result = CliRunner().invoke(main, given)
        key = "FILE" if command == "init" else "--out"
        lines = check(result, f"error: {key} = ", "the file system can write (")
        assert (result.exit_code == 2) == (kind in REFUSED), (kind, out, lines)
        assert not (folder / f"nowhere{suffix}").exists()


# --- hand-edited manifests -------------------------------------------------------------


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A simulation's folder and an evaluation's (of the simulation's first 4 s)."""
    folder = tmp_path_factory.mktemp("runs")
    simulated, evaluated = folder / "simulated", folder / "evaluated"
    assert (
        CliRunner().invoke(main, ["simulate", HOLD, *QUICK, "--out", str(simulated)]).exit_code == 0
    )
    motion = ["--motion", str(simulated / "timeline.csv"), "--between", "0", "4", "--no-report"]
    assert (
        CliRunner().invoke(main, ["evaluate", HOLD, *motion, "--out", str(evaluated)]).exit_code
        == 0
    )
    return {"simulation": simulated, "evaluation": evaluated}


FIELDS = {
    "simulation": ["problem_data", "problem_path", "solver", "recording", "problem_data.body"],
    "evaluation": [
        "recording",
        "recording.source",
        "recording.sha256",
        "recording.solver",
        "recording.between_s",
        "recording.resample_s",
        "recording.repeat_times",
        "recording.until_s",
        "solver",
    ],
}
DELETED = object()

scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**20), 10**20),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=30),
    st.sampled_from(["nullspace", "lexicographic", "recorded", "0 4", "[0, 4]", "a" * 300]),
)
values = st.one_of(
    scalars,
    st.lists(scalars, max_size=4),
    st.dictionaries(st.text(max_size=8), scalars, max_size=3),
    st.integers(1, 400).map(lambda depth: json.loads("[" * depth + "]" * depth)),
    st.just(DELETED),
)


@fuzzed(80)
@given(run=st.sampled_from(sorted(FIELDS)), data=st.data(), value=values)
def test_a_hand_edited_manifest_is_refused_naming_the_key(
    runs: dict[str, Path], run: str, data: st.DataObject, value: Any
) -> None:
    key = data.draw(st.sampled_from(FIELDS[run]))
    record = json.loads((runs[run] / "manifest.json").read_text())
    table, _, field = key.rpartition(".")
    node = record[table] if table else record
    if value is DELETED:
        node.pop(field, None)
    else:
        node[field] = value
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        manifest = folder / "manifest.json"
        manifest.write_text(json.dumps(record))
        shutil.copy(runs[run] / "summary.json", folder / "summary.json")
        result = CliRunner().invoke(main, ["rerun", str(manifest), "--out", str(folder / "re")])
        lines = check(result)
        if result.exit_code == 2:  # the manifest and its key, or the option read from it
            option = field.removesuffix("_s").removesuffix("_times")
            named = str(manifest) in lines[0] or f"--{option}" in lines[0]
            assert named and (field in lines[0] or f"--{option}" in lines[0] or table in lines[0])


# --- --set values, what-if values, heavy loads -----------------------------------------

SET_KEYS = [
    "title",
    "fatigue.strategy",
    "loads[0].mass_kg",
    "body.mass_kg",
    "tasks[0].elevation_deg",
    "fatigue.r_min",
    "body.sex",
    "nope.deeper",
]
texts = st.one_of(
    st.text(max_size=40).filter(lambda t: "\x00" not in t),
    st.integers(1, 5000).map(lambda n: "T" * n),
    st.integers(1, 3000).map(lambda n: "[" * n + "]" * n),
    st.integers(1, 800).map(lambda n: "{a=" * n + "1" + "}" * n),
    st.sampled_from(["1e308", "-1e308", "nan", "inf", "1" * 400, '"x', "[1, 2", "true", "0"]),
)


@fuzzed(80)
@given(key=st.sampled_from(SET_KEYS), value=texts, command=st.sampled_from(["validate", "solve"]))
def test_a_set_value_answers_or_is_refused_naming_the_file(
    key: str, value: str, command: str
) -> None:
    result = CliRunner().invoke(main, [command, HOLD, "--set", f"{key}={value}"])
    check(result, HOLD)


#: Titles: very long, in letters of two and three bytes, or anything ``texts`` gives.
titles = st.one_of(
    st.tuples(st.sampled_from(["T", "é", "数", "a b"]), st.integers(1, 5000)).map(
        lambda t: t[0] * t[1]
    ),
    texts,
)
whatif_values = st.one_of(
    st.tuples(st.just("title"), titles),
    st.tuples(
        st.sampled_from(["loads[0].mass_kg", "fatigue.strategy"]),
        st.one_of(texts, st.sampled_from(["1000", "999.9", "5e2", "0", "passive"])),
    ),
)


@fuzzed(15)
@given(key_value=whatif_values)
def test_a_whatif_value_answers_or_is_refused_naming_the_file(key_value: tuple[str, str]) -> None:
    key, value = key_value
    with tempfile.TemporaryDirectory() as name:
        args = ["whatif", HOLD, "--static", "--quiet", "--no-report", "--vary", f"{key}={value}"]
        result = CliRunner().invoke(main, [*args, "--out", str(Path(name) / "w")])
        check(result, HOLD)
        if key == "title" and set(value) <= set("Té数a b"):  # any title, however long
            assert result.exit_code == 0, result.stderr


@fuzzed(6)
@given(mass=st.sampled_from([0.0, 150.0, 1000.0, 1e5, -1.0]), json_out=st.booleans())
def test_sensitivity_under_any_load_answers_flagged_or_refuses(mass: float, json_out: bool) -> None:
    args = ["sensitivity", HOLD, "--set", f"loads[0].mass_kg={mass}"] + (
        ["--json"] if json_out else []
    )
    result = CliRunner().invoke(main, args)
    check(result, HOLD)
    if mass >= 150:  # over strength: an answer, flagged
        assert result.exit_code in (1, 2)


# --- body-tree regions -----------------------------------------------------------------


@fuzzed(30)
@given(
    region=st.one_of(
        st.sampled_from([*REGIONS, "moon", "hips", "Shoulder", "neck"]),
        st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,20}", fullmatch=True),
    )
)
def test_a_region_is_one_the_data_knows_or_is_refused_naming_them(region: str) -> None:
    text = template("tree").replace('region = "elbow"', f'region = "{region}"', 1)
    with tempfile.TemporaryDirectory() as name:
        problem = Path(name) / "tree.toml"
        problem.write_text(text)
        result = CliRunner().invoke(main, ["validate", str(problem)])
        check(result, str(problem), f"region = '{region}'", str(list(REGIONS)))
        assert (result.exit_code == 0) == (region in REGIONS)


# --- a file validate accepts, through the commands --------------------------------------

#: Commands run one after the other in one process on a file ``validate`` accepts.
SEQUENCE = [
    ("describe", ()),
    ("torques", ()),
    ("solve", ()),
    ("simulate", ("--duration", "10")),
    ("sensitivity", ()),
    ("compare", ()),
]


@fuzzed(20)
@given(case=cases())
def test_a_file_validate_accepts_never_crashes_a_command(case: Case) -> None:
    """One process, as a Python session or a batch worker runs them: a solver cached by one
    command must serve the next (``solve`` then ``simulate`` once crashed)."""
    with tempfile.TemporaryDirectory() as name:
        problem = Path(name) / "fuzzed.toml"
        problem.write_text(case.text)
        if CliRunner().invoke(main, ["validate", str(problem)]).exit_code != 0:
            return
        for command, options in SEQUENCE:
            with tempfile.TemporaryDirectory() as folder:
                ran = run_case(replace(case, command=command, options=options), Path(folder))
            assert not ran.problems, (case.source, case.mutations, command, ran.problems)
