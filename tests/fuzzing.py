"""Mutated problem files and command lines, and what every command must do with them.

Shared by the fuzz test (a fixed seed and example count in CI) and by
``benchmarks/fuzz.py`` (a larger campaign that prints its figures). A case is a problem
file (a shipped one with up to three mutations: plausible values at the edge of what the
model answers, perturbed numbers, keys deleted or added, types swapped, nan/inf/huge/tiny
numbers, unit slips, truncation, deep nesting) and one command line (with mutated
options too). Whatever the input, a command must:

- exit with code 0, 1 or 2;
- never print a traceback;
- on exit 2, say what is wrong in at most 3 lines naming the problem file;
- write no nan or inf into any answer, JSON or CSV (an error message, or a batch's
  reason for a failed case, may quote the bad value it refuses);
- finish within ``TIME_LIMIT_S``.
"""

from __future__ import annotations

import json
import math
import re
import time
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from click.testing import CliRunner
from hypothesis import strategies as st

from casadi_posture.cli import main

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
SHIPPED = {p.name: p.read_text() for p in sorted(PROBLEMS.glob("*.toml"))}

#: Longest a fuzzed command may run [s] (a 10-second simulation at 0.01 s steps included).
TIME_LIMIT_S = 60.0

WEIRD_NUMBERS = [
    math.nan,
    math.inf,
    -math.inf,
    1e308,
    -1e308,
    1e-300,
    -1e-300,
    0.0,
    -1.0,
    0,
    2147483648,
    1e12,
    35.0,
    -25.0,
    0.01,
]
WEIRD_VALUES = [*WEIRD_NUMBERS, "", "x", "nullspace", True, [], {}, [math.nan, 0, 0], [1, 2]]
UNKNOWN_KEYS = ["nope", "mass", "strength", "kind", "model", "x_m", "duration"]
#: Values a user might well write: valid, or at the edge of what the model can answer
#: (unreachable points, loads over strength, extreme bodies, other models).
PLAUSIBLE = {
    ("loads", 0, "mass_kg"): [0.0, 1.0, 5.0, 20.0, 60.0],
    ("tasks", 0, "point_m"): [[0.6, 0.0, 0.0], [0.2, 0.0, -0.1], [0.0, 0.0, -0.6], [0.0, 0.3, 0.0]],
    ("tasks", 0, "target_m"): [[0.6, 0.0, 0.0], [0.1, 0.0, -0.2]],
    ("tasks", 0, "priority"): [1, 2, 3],
    ("tasks", 1, "priority"): [1, 2],
    ("fatigue", "recovery_law"): ["3cc_r", "threshold", "continuous"],
    ("fatigue", "endurance"): ["rohmert", "frey_law_avin", "manenica"],
    ("fatigue", "strategy"): ["passive", "active"],
    ("fatigue", "fatigue_threshold"): [1.0, 0.6],
    ("fatigue", "recovery_threshold"): [0.1, 0.55],
    ("fatigue", "r_min"): [0.0, 1.0],
    ("fatigue", "epsilon_Nm"): [100.0, 1e-6],
    ("fatigue", "alpha_rad_per_Nm2"): [-1e-2, -1e-9],
    ("fatigue", "max_step_deg"): [30.0, 0.01],
    ("fatigue", "load_threshold_pct_mvc"): [0.0, 100.0],
    ("fatigue", "keep_levels"): [1, 2, 5],
    ("simulation", "time_step_s"): [0.5, 5.0, 60.0],
    ("solver", "name"): ["nullspace", "lexicographic"],
    ("solver", "max_iterations"): [1, 3, 100000],
    ("solver", "tolerance"): [1e-14, 1e-2],
    ("body", "sex"): ["female"],
    ("body", "stature_m"): [0.5, 2.5],
    ("body", "mass_kg"): [10.0, 300.0],
    ("body", "age_years"): [18.0, 100.0],
    ("posture_deg", "shoulder_flexion"): [-60.0, 0.0, 90.0, 179.0],
    ("posture_deg", "elbow_flexion"): [0.0, 149.0],
}
COMMANDS = [
    "validate",
    "describe",
    "torques",
    "solve",
    "simulate",
    "curve",
    "whatif",
    "compare",
    "batch",
    "sensitivity",
    "design",
    "duty-cycle",
]
VARY_KEYS = [
    "loads[0].mass_kg",
    "tasks[0].elevation_deg",
    "fatigue.strategy",
    "fatigue.r_min",
    "body.stature_m",
    "body.sex",
    "solver",
    "simulation.duration_s",
    "nope",
    "loads[9].mass_kg",
    "tasks[0].point_m",
]


@dataclass(frozen=True)
class Case:
    """A fuzzed problem file (its text, from ``source`` with ``mutations``) and command."""

    source: str
    mutations: tuple[str, ...]
    text: str
    command: str
    options: tuple[str, ...]


@dataclass
class Outcome:
    """What a command did with a case: exit code, seconds, and every rule it broke."""

    command: str
    exit_code: int
    seconds: float
    problems: list[str] = field(default_factory=list)


def toml_text(data: dict[str, Any]) -> str:
    """A TOML document of ``data`` (tables, arrays, strings, numbers, nan and inf)."""
    lines: list[str] = []
    _table(data, [], lines)
    return "\n".join(lines) + "\n"


def _table(data: dict[str, Any], path: list[str], lines: list[str]) -> None:
    plain = {k: v for k, v in data.items() if not _is_table(v) and not _is_table_array(v)}
    if path:
        lines.append(f"[{'.'.join(_key(p) for p in path)}]")
    lines += [f"{_key(k)} = {_value(v)}" for k, v in plain.items()]
    for key, value in data.items():
        if _is_table(value):
            _table(value, [*path, key], lines)
        elif _is_table_array(value):
            for item in value:
                lines.append(f"[[{'.'.join(_key(p) for p in [*path, key])}]]")
                lines += [f"{_key(k)} = {_value(v)}" for k, v in item.items()]


def _is_table(value: Any) -> bool:
    return isinstance(value, dict) and bool(value)


def _is_table_array(value: Any) -> bool:
    return (
        isinstance(value, list)
        and bool(value)
        and all(
            isinstance(v, dict) and v and not any(_is_table(x) for x in v.values()) for v in value
        )
    )


def _key(key: str) -> str:
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else json.dumps(key)


def _value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(value)


def _paths(data: Any, prefix: tuple = ()) -> list[tuple]:
    """Every key path in ``data`` (tables and arrays walked)."""
    out = []
    items = (
        data.items()
        if isinstance(data, dict)
        else enumerate(data)
        if isinstance(data, list)
        else ()
    )
    for key, value in items:
        out.append((*prefix, key))
        out += _paths(value, (*prefix, key))
    return out


def _get_parent(data: Any, path: tuple) -> tuple[Any, Any]:
    node = data
    for part in path[:-1]:
        node = node[part]
    return node, path[-1]


@st.composite
def cases(draw: Callable) -> Case:
    """A mutated shipped problem and a command line."""
    source = draw(st.sampled_from(sorted(SHIPPED)))
    data = tomllib.loads(SHIPPED[source])
    command = draw(st.sampled_from(COMMANDS))
    if command == "batch":  # batch has no --duration: keep its simulations short
        data.setdefault("simulation", {})["duration_s"] = 10.0
    mutations: list[str] = []
    truncate = False
    for _ in range(draw(st.integers(0, 3))):
        kind = draw(
            st.sampled_from(
                ["plausible"] * 4
                + ["perturb"] * 2
                + ["delete", "set", "add", "swap", "slip", "truncate", "nest", "schedule"]
            )
        )
        paths = _paths(data)
        if kind == "truncate":
            truncate = True
            mutations.append("truncate")
            continue
        if kind == "nest":
            depth = draw(st.integers(10, 600))
            data["deep"] = json.loads("[" * depth + "]" * depth)
            mutations.append(f"nest {depth}")
            continue
        if kind == "schedule":
            data["schedule"] = {
                "t_on_s": draw(st.sampled_from([30.0, 60.0, 90.0, *WEIRD_VALUES])),
                "t_off_s": draw(st.sampled_from([0.0, 15.0, 30.0, *WEIRD_VALUES])),
            }
            mutations.append("schedule")
            continue
        if kind == "add":
            tables = [p for p in paths if isinstance(_get_parent(data, p)[0][p[-1]], dict)]
            target = data if not tables else _node(data, draw(st.sampled_from(tables)))
            key = draw(st.sampled_from(UNKNOWN_KEYS))
            target[key] = draw(st.sampled_from(WEIRD_VALUES))
            mutations.append(f"add {key}")
            continue
        if kind == "plausible":
            key, values = draw(st.sampled_from(sorted(PLAUSIBLE.items(), key=str)))
            try:
                parent, last = _get_parent(data, key)
                if isinstance(parent, list) and last >= len(parent):
                    continue
                parent[last] = draw(st.sampled_from(values))
            except (KeyError, IndexError, TypeError):
                continue
            mutations.append(f"set {'.'.join(map(str, key))}")
            continue
        numbers = [p for p in paths if _is_number(_node(data, p))]
        if kind == "perturb" and numbers:
            path = draw(st.sampled_from(numbers))
            parent, last = _get_parent(data, path)
            parent[last] = parent[last] * draw(st.floats(0.5, 2.0)) + draw(st.floats(-0.2, 0.2))
            mutations.append(f"perturb {'.'.join(map(str, path))}")
            continue
        if not paths or kind == "perturb":
            continue
        path = draw(st.sampled_from(paths))
        parent, last = _get_parent(data, path)
        if kind == "delete":
            del parent[last]
        elif kind == "set":
            parent[last] = draw(st.sampled_from(WEIRD_VALUES))
        elif kind == "swap":
            value = parent[last]
            parent[last] = draw(st.sampled_from([str(value), [value], {"v": value}, True]))
        elif kind == "slip" and _is_number(parent[last]):
            parent[last] = parent[last] * draw(st.sampled_from([100, 1000, 1e-3, -1]))
        mutations.append(f"{kind} {'.'.join(map(str, path))}")
    text = toml_text(data)
    if truncate:
        text = text[: draw(st.integers(0, len(text)))]
    options = draw(_options(command, data))
    return Case(source, tuple(mutations), text, command, tuple(options))


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _node(data: Any, path: tuple) -> Any:
    for part in path:
        data = data[part]
    return data


#: Plausible values of the varied keys, and of the numeric options.
VARY_VALUES = {
    "loads[0].mass_kg": ["0", "2.5", "5", "20"],
    "tasks[0].elevation_deg": ["0", "-25", "-45", "90"],
    "fatigue.strategy": ["active", "passive"],
    "fatigue.r_min": ["0", "0.5", "1"],
    "body.stature_m": ["1.5", "1.9"],
    "body.sex": ["male", "female"],
    "solver": ["nullspace", "lexicographic"],
    "simulation.duration_s": ["10", "60"],
    "nope": ["1"],
    "loads[9].mass_kg": ["1"],
    "tasks[0].point_m": ["[0.35, 0.0, -0.25]", "[0.6, 0.0, 0.0]", "[35, 0, -25]"],
}


@st.composite
def _design_free(draw: Callable, data: dict) -> str:
    """A ``--free KEY=LO:HI``: two times in three a target coordinate of the file's own
    tasks within bounds around its value, else a key or bounds from the lists below."""
    tasks = data.get("tasks") if isinstance(data.get("tasks"), list) else []
    own = [
        (f"tasks[{i}].{name}[{k}]", point[k])
        for i, task in enumerate(tasks)
        if isinstance(task, dict)
        for name in ("point_m", "target_m")
        if isinstance(point := task.get(name), list) and len(point) == 3
        for k in range(3)
        if _is_number(point[k]) and math.isfinite(point[k])
    ]
    if own and draw(st.integers(0, 2)):
        key, value = draw(st.sampled_from(own))
        below, above = draw(st.sampled_from([(0.2, 0.1), (0.05, 0.3), (0.0, 0.2)]))
        return f"{key}={value - below:.4g}:{value + above:.4g}"
    return f"{draw(st.sampled_from(DESIGN_KEYS))}={draw(st.sampled_from(DESIGN_BOUNDS))}"


SENSITIVITY_KINDS = ["load", "target", "posture", "body", "strength", "passive", "endurance"]
DESIGN_KEYS = [
    "tasks[0].point_m[2]",
    "tasks[0].target_m[2]",
    "tasks[1].target_m[2]",
    "tasks[0].point_m[2],tasks[1].target_m[2]",
    "tasks[2].target_m[2],tasks[3].target_m[2]",
    "tasks[0].point_m",
    "loads[0].mass_kg",
    "nope",
]
#: Bounds in m: plausible, reversed, empty, not finite, a cm-for-m slip, not numbers.
DESIGN_BOUNDS = ["-0.5:0.1", "-0.3:-0.2", "1.0:1.6", "0.1:-0.5", "1:1", "nan:1", "-50:10", "a:b"]
DESIGN_OBJECTIVES = ["endurance", "capable-male", "capable-female"]
WEIRD_OPTIONS = ["nan", "inf", "-1", "1e308", "abc", "", "0", "1e-9"]


def _maybe_weird(draw: Callable, plausible: list[str]) -> str:
    """A plausible value two times in three, else a weird one."""
    return draw(st.sampled_from(plausible * 2 + WEIRD_OPTIONS[: len(plausible)]))


@st.composite
def _options(draw: Callable, command: str, data: dict) -> list[str]:
    if command in ("torques", "solve", "describe"):
        options = ["--json"] if draw(st.booleans()) else []
        if command == "torques" and draw(st.booleans()):
            name = draw(st.sampled_from(["shoulder_flexion", "elbow_flexion", "knee", ""]))
            options += ["--posture", f"{name}={_maybe_weird(draw, ['0', '45', '90', '200'])}"]
        if command == "solve" and draw(st.booleans()):
            options += ["--solver", draw(st.sampled_from(["nullspace", "lexicographic", "x"]))]
        return options
    if command == "simulate":
        options = ["--duration", _maybe_weird(draw, ["10", "20", "5"])]
        if draw(st.booleans()):
            options += ["--solver", draw(st.sampled_from(["nullspace", "lexicographic"]))]
        if draw(st.booleans()):
            options += ["--r-min", _maybe_weird(draw, ["0", "0.5", "1"])]
        return options
    if command == "curve":
        dof = draw(st.sampled_from(["elbow_flexion", "shoulder_flexion", "nope"]))
        suffix = draw(st.sampled_from(["png", "png", "svg", "xyz", ""]))
        return ["--dof", dof, "--out", f"FIG.{suffix}" if suffix else "FIG"]
    if command == "batch":
        return ["--quiet"] + (["--solver", "nullspace"] if draw(st.booleans()) else [])
    if command == "whatif":
        key = draw(st.sampled_from(VARY_KEYS))
        values = draw(st.lists(st.just(None), min_size=1, max_size=4))
        chosen = [_maybe_weird(draw, VARY_VALUES[key]) for _ in values]
        options = ["--vary", f"{key}={','.join(chosen)}", "--quiet"]
        options += (
            ["--static"] if draw(st.integers(0, 3)) else ["--vary", "simulation.duration_s=10"]
        )
        if draw(st.integers(0, 5)) == 0:
            options += ["--vary", "loads[0].mass_kg=" + ",".join(str(v) for v in range(1, 40))]
            options += ["--vary", "body.mass_kg=" + ",".join(str(v) for v in range(40, 80))]
        return options
    if command == "sensitivity":
        options = ["--json"] if draw(st.booleans()) else []
        if draw(st.booleans()):
            options += ["--top", _maybe_weird(draw, ["1", "5", "40"])]
        if draw(st.booleans()):
            options += ["--kind", draw(st.sampled_from([*SENSITIVITY_KINDS, "loads"]))]
        return options + (["--out", "FIG"] if draw(st.booleans()) else [])
    if command == "design":
        options = []
        for _ in range(draw(st.integers(1, 2))):
            options += ["--free", draw(_design_free(data))]
        if draw(st.booleans()):
            options += ["--objective", draw(st.sampled_from(DESIGN_OBJECTIVES))]
        if draw(st.booleans()):
            options += ["--starts", _maybe_weird(draw, ["1", "2", "3"])]
        if draw(st.booleans()):
            options += ["--json"]
        return options + (["--out", "FIG"] if draw(st.booleans()) else [])
    if command == "duty-cycle":
        options = ["--t-off", _maybe_weird(draw, ["0", "30", "15,60", "30,30"])]
        options += ["--horizon", _maybe_weird(draw, ["60", "120", "300"])]
        if draw(st.booleans()):
            options += ["--tolerance", _maybe_weird(draw, ["5", "20"])]
        if draw(st.booleans()):
            options += ["--json"]
        return options + (["--out", "FIG"] if draw(st.booleans()) else [])
    return []


def run_case(case: Case, folder: Path) -> Outcome:
    """Run ``case`` in ``folder`` (in-process) and check every rule."""
    problem = folder / "fuzzed.toml"
    problem.write_text(case.text)
    out = folder / "out"
    options = [o.replace("FIG", str(folder / "fig")) for o in case.options]
    args = [case.command, str(problem), *options]
    if case.command in ("simulate", "whatif", "batch"):
        args += ["--out", str(out)]
    start = time.monotonic()
    result = CliRunner().invoke(main, args)
    seconds = time.monotonic() - start
    outcome = Outcome(case.command, result.exit_code, seconds)
    problems = outcome.problems
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        problems.append(f"raised {type(result.exception).__name__}: {result.exception}")
    if result.exit_code not in (0, 1, 2):
        problems.append(f"exit code {result.exit_code}")
    text = result.stdout + result.stderr
    if "Traceback" in text or "internal error" in text:
        problems.append("a traceback or an internal error in the output")
    if result.exit_code == 2:
        lines = result.stderr.strip().splitlines()
        if not lines or len(lines) > 3:
            problems.append(f"exit 2 with {len(lines)} lines on stderr")
        elif str(problem) not in result.stderr:
            problems.append(f"exit 2 without naming the file: {lines[0]}")
    answers = [line for line in result.stdout.splitlines() if "failed" not in line]
    if result.exit_code in (0, 1) and re.search(r"\b(nan|NaN|inf|Infinity)\b", "\n".join(answers)):
        problems.append("nan or inf in an answer")
    if "--json" in options and result.exit_code in (0, 1):
        problems += _json_problems(result.stdout, "stdout")
    for path in sorted(folder.rglob("*")):
        if path.suffix == ".json":
            problems += _json_problems(path.read_text(), path.name)
        elif path.suffix == ".csv" and re.search(
            r"(^|,)(nan|inf|-inf)(,|$)", path.read_text(), re.MULTILINE
        ):
            problems.append(f"nan or inf in {path.name}")
    if seconds > TIME_LIMIT_S:
        problems.append(f"took {seconds:.1f} s")
    return outcome


def _json_problems(text: str, name: str) -> list[str]:
    def refuse(constant: str) -> None:
        raise ValueError(constant)

    try:
        json.loads(text, parse_constant=refuse)
    except ValueError as error:
        return [f"{name} is not strict JSON ({str(error)[:60]})"]
    return []
