"""pandas DataFrames of results, for users who have pandas (an optional extra)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any


def frame(data: Mapping[str, Sequence[Any]] | Sequence[Mapping[str, Any]]) -> Any:
    """A ``pandas.DataFrame`` of named columns or of rows; pandas is imported here only."""
    try:
        import pandas
    except ImportError:
        raise ImportError(
            "results become DataFrames with pandas: pip install 'casadi_posture[pandas]'"
        ) from None
    return pandas.DataFrame(data)
