"""Columns of Python values as Arrow arrays, built from their buffers: the types pyarrow
infers from a list (double, int64, string; null for a column without a value; None an
empty cell), without the pandas import its inference makes on first use, a quarter of a
second of every run's files. Other columns are left to pyarrow's own inference."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

#: The largest and smallest int64; the type of an empty cell.
INT64, NONE = np.iinfo(np.int64), type(None)


def column(values: Sequence[Any]) -> pa.Array:
    """``values`` as the Arrow array ``pyarrow.array(values)`` makes."""
    n = len(values)
    kinds = set(map(type, values))
    nulls = values.count(None) if NONE in kinds else 0
    kinds.discard(NONE)
    if not kinds:
        return pa.nulls(n)
    present = [v is not None for v in values] if nulls else None
    valid = None if present is None else pa.py_buffer(np.packbits(present, bitorder="little"))
    if kinds == {str}:
        data = [v.encode() if v is not None else b"" for v in values]
        ends = np.cumsum([0, *map(len, data)])
        if ends[-1] <= np.iinfo(np.int32).max:
            offsets = pa.py_buffer(ends.astype(np.int32))
            text = pa.py_buffer(b"".join(data))
            return pa.Array.from_buffers(pa.string(), n, [valid, offsets, text], nulls)
    elif kinds <= {int, float, np.float64} and (kinds - {int} or _fits_int64(values, nulls)):
        kind = (np.float64, pa.float64()) if kinds - {int} else (np.int64, pa.int64())
        numbers = np.array([0 if v is None else v for v in values] if nulls else values, kind[0])
        return pa.Array.from_buffers(kind[1], n, [valid, pa.py_buffer(numbers)], nulls)
    return pa.array(values)


def _fits_int64(values: Sequence[Any], nulls: int) -> bool:
    numbers = [v for v in values if v is not None] if nulls else values
    return INT64.min <= min(numbers) and max(numbers) <= INT64.max


def write_parquet(columns: dict[str, Sequence[Any]], path: Path) -> None:
    """Named columns (``column`` each) into a Parquet file."""
    arrays = [column(values) for values in columns.values()]
    pq.write_table(pa.Table.from_arrays(arrays, names=list(columns)), str(path))
