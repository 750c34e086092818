"""Virtual workers drawn from measured distributions (docs/population.md): stature, body
mass and age per sex from ANSUR II (stature normal, mass lognormal, age the survey's own
distribution, joined by a Gaussian copula with the survey's correlations), and each muscle
group's strength a lognormal factor of the shipped default for that body, with the group's
population spread and a common factor shared by one person's groups."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from statistics import NormalDist

import numpy as np

from casadi_posture.biomech.capability import SEXES, Sex, strength_spread
from casadi_posture.data import parameters

#: A population of more workers than this per sex needs ``max_workers`` raised.
MAX_WORKERS = 100_000


@dataclass(frozen=True)
class Worker:
    """One virtual worker: a number (from 0, per sex), sex, stature [m], body mass [kg], and
    per muscle group (its name without side: both sides share it) the factor its strength
    takes on the shipped default for a body of this size, sex and age [years]."""

    number: int
    sex: Sex
    stature_m: float
    mass_kg: float
    strength: Mapping[str, float]
    age_years: float

    @property
    def name(self) -> str:
        """``female-0007``: the worker's case name in a population run."""
        return f"{self.sex}-{self.number:04d}"


def anthropometry(sex: Sex) -> dict[str, float]:
    """ANSUR II's stature [m] and ln body mass [ln kg] means and SDs and their correlation
    for ``sex``, and the normal-score correlations of age with each (data/population.toml)."""
    table = parameters.load("population")
    keys = ("stature_mean", "stature_sd", "log_mass_mean", "log_mass_sd")
    keys += ("stature_age_correlation", "log_mass_age_correlation")
    out = {k: float(table[f"population.ansur_2.{sex}.{k}"].value) for k in keys}
    out["correlation"] = float(
        table[f"population.ansur_2.{sex}.stature_log_mass_correlation"].value
    )
    return out


def ages(sex: Sex) -> tuple[int, np.ndarray]:
    """ANSUR II's first age [years] and the share of its ``sex`` at each whole year from it."""
    table = parameters.load("population")
    counts = np.asarray(table[f"population.ansur_2.{sex}.age_counts"].value, dtype=float)
    return int(table[f"population.ansur_2.{sex}.age_first_years"].value), counts / counts.sum()


def age_at(sex: Sex, u: np.ndarray) -> np.ndarray:
    """The age [years] at each quantile ``u`` in (0, 1] of ANSUR II's ``sex``: the whole year
    whose share of the survey holds ``u``, and the fraction of that year where ``u`` falls in
    its share, so that the whole years are the survey's and the age runs on within a year."""
    first, share = ages(sex)
    cdf = np.cumsum(share)
    year = np.minimum(np.searchsorted(cdf, u, side="left"), share.size - 1)
    below = np.where(year > 0, cdf[year - 1], 0.0)
    return first + year + np.clip((u - below) / share[year], 0.0, 1.0 - 1e-9)


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
    ln mass bivariate normal (``anthropometry``), age the survey's at the quantile of a
    third normal score correlated with them as the survey's (a Gaussian copula: ``age_at``);
    per group of ``groups`` (named without side) a strength factor exp(σ z − σ²/2), mean 1,
    CV the group's population spread (``strength_spread``), with z = √ρ·z_person +
    √(1−ρ)·z_group: any two groups of one person correlated ``correlation`` (default
    ``group_correlation``)."""
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
        aging = rng.standard_normal(n)
        if sex not in sexes:
            continue
        a = anthropometry(sex)
        r = a["correlation"]
        stature = a["stature_mean"] + a["stature_sd"] * body[:, 0]
        log_mass = a["log_mass_mean"] + a["log_mass_sd"] * (
            r * body[:, 0] + math.sqrt(1 - r * r) * body[:, 1]
        )
        # the age's normal score: the third row of the Cholesky factor of the correlations
        first = a["stature_age_correlation"]
        second = (a["log_mass_age_correlation"] - r * first) / math.sqrt(1 - r * r)
        score = first * body[:, 0] + second * body[:, 1]
        score += math.sqrt(1 - first**2 - second**2) * aging
        age = age_at(sex, np.array([_NORMAL.cdf(float(z)) for z in score]))
        z = math.sqrt(rho) * person[:, None] + math.sqrt(1 - rho) * own
        sigma = np.array([_sigma(strength_spread(g)[0][sex]) for g in names])
        factor = np.exp(sigma * z - sigma**2 / 2)
        for k in range(n):
            strength = dict(zip(names, map(float, factor[k]), strict=True))
            mass = float(np.exp(log_mass[k]))
            workers.append(Worker(k, sex, float(stature[k]), mass, strength, float(age[k])))
    return workers


_NORMAL = NormalDist()


def _sigma(cv: float) -> float:
    """The lognormal σ whose coefficient of variation is ``cv``."""
    return math.sqrt(math.log(1.0 + cv * cv))
