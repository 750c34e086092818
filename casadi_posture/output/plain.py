"""Plain data for the JSON, CSV and Parquet files: Python numbers, finite only.

An infinite or undefined number becomes ``None`` (JSON ``null``, an empty CSV cell); each
file documents what ``null`` means in its place (an unlimited endurance, a threshold
never reached). No file ever carries ``nan`` or ``inf``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from typing import Any

import numpy as np


def plain(value: Any) -> Any:
    """``value`` with numpy types made Python and every non-finite float made ``None``."""
    if isinstance(value, np.ndarray):
        return [plain(v) for v in value.tolist()]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    return value


def dumps(value: Any) -> str:
    """Indented JSON of ``plain(value)``; refuses nan and inf should any remain."""
    return json.dumps(plain(value), indent=2, allow_nan=False)
