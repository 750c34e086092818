"""The shipped data files: every parameter has a unit, a source and a status."""

from __future__ import annotations

from importlib import resources

import pytest

from casadi_posture.data import parameters

STEMS = sorted(
    p.name.removesuffix(".toml")
    for p in resources.files("casadi_posture.data").iterdir()
    if p.name.endswith(".toml")
)


def test_data_files_are_found() -> None:
    assert {"anthropometry_de_leva_1996", "endurance", "fatigue", "joints", "strength"} <= set(
        STEMS
    )


@pytest.mark.parametrize("stem", STEMS)
def test_every_parameter_is_documented(stem: str) -> None:
    table = parameters.load(stem)
    assert table
    for name, record in table.items():
        assert name == record.name and name.startswith(stem + ".")
        assert record.unit and record.source and record.status in ("verified", "estimate")


def test_source_and_status_are_inherited_and_overridable() -> None:
    out: dict[str, parameters.Parameter] = {}
    parameters._collect(
        {
            "source": "S",
            "status": "verified",
            "a": {"value": 1, "unit": "m"},
            "b": {"status": "estimate", "c": {"value": 2, "unit": "s", "evidence": "E"}},
        },
        "t",
        {},
        out,
    )
    assert out["t.a"].source == "S" and out["t.a"].status == "verified"
    assert out["t.b.c"].status == "estimate" and out["t.b.c"].evidence == "E"


def test_a_parameter_without_unit_is_rejected() -> None:
    with pytest.raises(ValueError, match="lacks unit"):
        parameters._collect({"source": "S", "status": "verified", "a": {"value": 1}}, "t", {}, {})
