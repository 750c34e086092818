"""timeline.parquet's columns built from their buffers: the arrays pyarrow's own inference
makes from the same lists, without importing pandas."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")

from casadi_posture.output.arrow_columns import column, write_parquet  # noqa: E402

COLUMNS = {
    "floats": [0.5, None, -1e300, float("nan"), 2.0],
    "floats and ints": [1, 2.5, None, 3, -4],
    "numpy floats": [np.float64(0.25), None, 1.0, 2.0, 3.0],
    "ints": [0, 1, None, -(2**63), 2**63 - 1],
    "too large for int64": [2**64, 1, None, 2, 3],
    "strings": ["hold", None, "rest", "épaule", ""],
    "empty cells only": [None] * 5,
    "booleans": [True, False, None, True, True],
    "strings and numbers": ["a", 1, None, 2.0, "b"],
}


#: Columns pyarrow itself refuses; a column left to pyarrow's inference (it imports pandas).
REFUSED, INFERRED = ("too large for int64", "strings and numbers"), ("booleans",)


def _cells(array: pa.Array) -> list:
    """An array's values, NaN as a string (NaN equals nothing, not even itself)."""
    return ["NaN" if isinstance(v, float) and v != v else v for v in array.to_pylist()]


@pytest.mark.parametrize("name", list(COLUMNS))
def test_a_column_is_the_array_pyarrow_infers(name: str) -> None:
    values = COLUMNS[name]
    if name in REFUSED:
        with pytest.raises(Exception) as theirs:
            pa.array(values)
        with pytest.raises(type(theirs.value)):
            column(values)
        return
    expected, got = pa.array(values), column(values)
    assert got.type == expected.type and _cells(got) == _cells(expected)
    assert got.null_count == expected.null_count == values.count(None)
    assert column([]).equals(pa.array([]))


def test_a_parquet_file_reads_back_its_columns_without_pandas(tmp_path) -> None:
    """In a fresh interpreter: writing the file imports no pandas, and it reads back."""
    columns = {k: v for k, v in COLUMNS.items() if k not in REFUSED + INFERRED}
    path = tmp_path / "t.parquet"
    script = (
        "import sys, pickle; from pathlib import Path\n"
        "from casadi_posture.output.arrow_columns import write_parquet\n"
        f"write_parquet(pickle.loads({__import__('pickle').dumps(columns)!r}), Path(sys.argv[1]))\n"
        "print('pandas' in sys.modules)\n"
    )
    done = subprocess.run([sys.executable, "-c", script, str(path)], capture_output=True, text=True)
    assert done.returncode == 0 and done.stdout.strip() == "False", done.stderr
    table = pq.read_table(path)
    assert table.column_names == list(columns)
    for name, values in columns.items():
        assert _cells(table[name].combine_chunks()) == _cells(pa.array(values)), name
    write_parquet(columns, tmp_path / "here.parquet")
    here = pq.read_table(tmp_path / "here.parquet")
    assert here.schema == table.schema
    for name in columns:
        assert _cells(here[name].combine_chunks()) == _cells(table[name].combine_chunks())
