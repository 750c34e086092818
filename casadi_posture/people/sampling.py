"""Virtual workers drawn from measured distributions (docs/population.md): stature and
body mass per sex from ANSUR II (stature normal, mass lognormal, correlated as in the
survey), and each muscle group's strength a lognormal factor of the shipped default for
that body, with the group's population spread and a common factor shared by one person's
groups."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from casadi_posture.biomech.capability import SEXES, Sex, strength_spread
from casadi_posture.data import parameters

#: A population of more workers than this per sex needs ``max_workers`` raised.
MAX_WORKERS = 100_000


@dataclass(frozen=True)
class Worker:
    """One virtual worker: a number (from 0, per sex), sex, stature [m], body mass [kg], and
    per muscle group (its name without side: both sides share it) the factor its strength
    takes on the shipped default for a body of this size and sex."""

    number: int
    sex: Sex
    stature_m: float
    mass_kg: float
    strength: Mapping[str, float]

    @property
    def name(self) -> str:
        """``female-0007``: the worker's case name in a population run."""
        return f"{self.sex}-{self.number:04d}"


def anthropometry(sex: Sex) -> dict[str, float]:
    """ANSUR II's stature [m] and ln body mass [ln kg] means and SDs and their correlation
    for ``sex`` (data/population.toml)."""
    table = parameters.load("population")
    keys = ("stature_mean", "stature_sd", "log_mass_mean", "log_mass_sd")
    out = {k: float(table[f"population.ansur_2.{sex}.{k}"].value) for k in keys}
    out["correlation"] = float(
        table[f"population.ansur_2.{sex}.stature_log_mass_correlation"].value
    )
    return out


def group_correlation() -> float:
    """The correlation of one person's strengths in two muscle groups (an estimate)."""
    return float(parameters.load("population")["population.strength.group_correlation"].value)


def draw_workers(
    n: int,
    sexes: Sequence[Sex],
    groups: Sequence[str],
    seed: int,
    *,
    correlation: float | None = None,
) -> list[Worker]:
    """``n`` workers of each sex of ``sexes``, deterministic for ``seed`` (one stream per
    sex: the men drawn are the same with or without the women). Per worker: stature and
    ln mass bivariate normal (``anthropometry``); per group of ``groups`` (named without
    side) a strength factor exp(σ z − σ²/2), mean 1, CV the group's population spread
    (``strength_spread``), with z = √ρ·z_person + √(1−ρ)·z_group: any two groups of one
    person correlated ``correlation`` (default ``group_correlation``)."""
    if not 1 <= n <= MAX_WORKERS:
        raise ValueError(f"n: 1 to {MAX_WORKERS} workers per sex, got {n}")
    rho = group_correlation() if correlation is None else correlation
    if not 0.0 <= rho <= 1.0:
        raise ValueError(f"correlation: 0 to 1, got {rho}")
    names = list(dict.fromkeys(groups))
    workers = []
    for sex, stream in zip(SEXES, np.random.SeedSequence(seed).spawn(len(SEXES)), strict=True):
        rng = np.random.default_rng(stream)
        body = rng.standard_normal((n, 2))
        person = rng.standard_normal(n)
        own = rng.standard_normal((n, len(names)))
        if sex not in sexes:
            continue
        a = anthropometry(sex)
        r = a["correlation"]
        stature = a["stature_mean"] + a["stature_sd"] * body[:, 0]
        log_mass = a["log_mass_mean"] + a["log_mass_sd"] * (
            r * body[:, 0] + math.sqrt(1 - r * r) * body[:, 1]
        )
        z = math.sqrt(rho) * person[:, None] + math.sqrt(1 - rho) * own
        sigma = np.array([_sigma(strength_spread(g)[0][sex]) for g in names])
        factor = np.exp(sigma * z - sigma**2 / 2)
        for k in range(n):
            strength = dict(zip(names, map(float, factor[k]), strict=True))
            workers.append(Worker(k, sex, float(stature[k]), float(np.exp(log_mass[k])), strength))
    return workers


def _sigma(cv: float) -> float:
    """The lognormal σ whose coefficient of variation is ``cv``."""
    return math.sqrt(math.log(1.0 + cv * cv))
