"""Proportions of a population with their confidence intervals."""

from __future__ import annotations

import math

#: The standard normal quantile of a two-sided 95 % interval.
Z_95 = 1.959963984540054


def wilson(count: int, n: int) -> tuple[float, float]:
    """The Wilson score 95 % interval of the proportion ``count`` / ``n`` (n ≥ 1): inside
    [0, 1], and not empty at 0 or ``n`` as the normal approximation's is."""
    p, z2 = count / n, Z_95 * Z_95
    centre = (p + z2 / (2 * n)) / (1 + z2 / n)
    half = Z_95 * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / (1 + z2 / n)
    return max(0.0, centre - half), min(1.0, centre + half)
