"""The fields of a run's manifest.json that ``rerun`` reads, as a schema: a hand-edited
manifest (a value that is null, a number, a list or a string where something else was
written) is refused before anything runs, in one line naming the file, the key, the value
and what was expected."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from casadi_posture.errors import MISSING, ProblemError
from casadi_posture.ik.solvers import SOLVER_NAMES

Finite = Annotated[float, Field(allow_inf_nan=False)]
Positive = Annotated[float, Field(gt=0, allow_inf_nan=False)]


class _Fields(BaseModel):
    """Values exactly as ``simulate`` and ``evaluate`` write them (no "5" for 5, no true for
    1); the manifest's other keys are records for people, not read."""

    model_config = ConfigDict(strict=True, extra="ignore", frozen=True)


class RecordingRead(_Fields):
    """How ``evaluate`` read its recording: the file and the options it was read with."""

    source: str = Field(description="the recording's path, a string")
    sha256: str = Field(
        pattern=r"^[0-9a-f]{64}$", description="the recording's SHA-256, 64 hexadecimal digits"
    )
    solver: Literal[SOLVER_NAMES] | None = Field(
        None, description=f"null or one of {list(SOLVER_NAMES)}"
    )
    between_s: Annotated[list[Finite], Field(min_length=2, max_length=2)] | None = Field(
        None, description="null or a pair [START, END] of times in s, START before END"
    )
    resample_s: Positive | None = Field(None, description="null or a step in s above 0")
    repeat_times: Annotated[int, Field(ge=1)] | None = Field(
        None, description="null or a whole number of repetitions, at least 1"
    )
    until_s: Positive | None = Field(None, description="null or a time in s above 0")

    @field_validator("between_s")
    @classmethod
    def _in_order(cls, between: list[float] | None) -> list[float] | None:
        if between is not None and not between[0] < between[1]:
            raise ValueError("START before END")
        return between

    def options(self) -> dict[str, Any]:
        """The reading options as ``api.evaluate`` takes them."""
        between = None if self.between_s is None else (self.between_s[0], self.between_s[1])
        return {
            "solver": self.solver,
            "between_s": between,
            "resample_s": self.resample_s,
            "repeat_times": self.repeat_times,
            "until_s": self.until_s,
        }


class Manifest(_Fields):
    """What ``rerun`` repeats: the problem's data after its overrides, the file it came from,
    the solver, and for an evaluation how its recording was read."""

    problem_path: str = Field(description="the problem file's path, a string")
    problem_data: dict[str, Any] = Field(
        description="the problem's tables after its overrides, a table"
    )
    solver: str = Field(description=f"the simulation's solver, one of {list(SOLVER_NAMES)}")
    recording: RecordingRead | None = Field(
        None, description="null (a simulation) or the table evaluate writes (an evaluation)"
    )


def read_manifest(path: Path) -> Manifest:
    """The fields ``rerun`` reads from the manifest.json at ``path``; anything else is a
    ``ProblemError`` naming the file, the key, the value and what was expected."""
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ProblemError(path, None, None, "the file does not exist") from None
    except (OSError, UnicodeDecodeError, ValueError, RecursionError) as error:
        raise ProblemError(path, None, None, f"a manifest.json ({error})") from None
    if not isinstance(record, dict):
        expected = "a manifest.json written by simulate or evaluate (a JSON object)"
        raise ProblemError(path, None, None, expected)
    try:
        manifest = Manifest.model_validate(record)
    except ValidationError as error:
        raise _refused(path, error, record) from None
    if manifest.recording is None and manifest.solver not in SOLVER_NAMES:
        expected = f"one of {list(SOLVER_NAMES)} (a simulation's: its recording is null)"
        raise ProblemError(path, "solver", _AsJson(manifest.solver), expected)
    return manifest


def _refused(path: Path, error: ValidationError, record: dict[str, Any]) -> ProblemError:
    """The first schema error as a ``ProblemError``: the field's key, the value it holds and
    the field's description."""
    loc = error.errors(include_url=False)[0]["loc"]
    model: type[_Fields] | None = Manifest
    node: Any = record
    names: list[str] = []
    description = "a manifest.json written by simulate or evaluate"
    for part in loc:
        if model is None or not isinstance(part, str) or part not in model.model_fields:
            break
        names.append(part)
        description = model.model_fields[part].description or description
        node = node.get(part, MISSING) if isinstance(node, dict) else MISSING
        model = RecordingRead if part == "recording" else None
    value = node if node is MISSING else _AsJson(node)
    return ProblemError(path, ".".join(names) or None, value, description)


class _AsJson:
    """A value from a JSON file, shown as the file writes it (null, true, [1, 2])."""

    def __init__(self, value: Any) -> None:
        self.value = value

    def __repr__(self) -> str:
        return json.dumps(self.value, ensure_ascii=False)
