"""write_table formats each row in one go; its files are those of the csv module writing
the cells one by one (floats to 10 significant digits, None empty), byte for byte."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import hypothesis.strategies as st
from conftest import PROBLEMS
from hypothesis import given, settings

from casadi_posture import api
from casadi_posture.output.results import event_columns, timeline_columns, write_table


def _by_the_csv_module(columns: dict[str, list[Any]], path: Path) -> None:
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(columns)
        for row in zip(*columns.values(), strict=True):
            writer.writerow(
                ["" if v is None else f"{v:.10g}" if isinstance(v, float) else v for v in row]
            )


def _same(columns: dict[str, list[Any]], folder: Path) -> bool:
    write_table(columns, folder / "fast.csv")
    _by_the_csv_module(columns, folder / "csv.csv")
    return (folder / "fast.csv").read_bytes() == (folder / "csv.csv").read_bytes()


CELLS = st.one_of(
    st.none(),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(10**20), max_value=10**20),
    st.booleans(),
    st.text(alphabet=st.sampled_from('ab ,"\r\n;%é-'), max_size=6),
)


@settings(max_examples=200, deadline=None)
@given(
    st.integers(min_value=0, max_value=6).flatmap(
        lambda rows: st.lists(
            st.one_of(
                st.lists(st.floats(), min_size=rows, max_size=rows),
                st.lists(st.integers(), min_size=rows, max_size=rows),
                st.lists(CELLS, min_size=rows, max_size=rows),
            ),
            max_size=5,
        )
    )
)
def test_any_columns_are_written_as_the_csv_module_writes_them(tmp_path_factory, columns) -> None:
    folder = tmp_path_factory.mktemp("csv")
    assert _same({f"c{k}": values for k, values in enumerate(columns)}, folder)


def test_a_run_s_timeline_and_events_are_written_as_before(tmp_path) -> None:
    problem = api.load(PROBLEMS / "holding_m45.toml", {"simulation.duration_s": 400.0})
    result = api.simulate(problem).result
    assert _same(timeline_columns(result), tmp_path)
    assert _same(event_columns(result), tmp_path)
    assert _same({}, tmp_path)  # no column: an empty header line
