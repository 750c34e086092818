"""Fatigue state of each half-joint over time, selectable by name (docs/model.md).

Both models are vectorised over the n half-joints of a body; ``regions[i]`` is the joint
region (``"shoulder"``, ``"elbow"``, …) of half-joint i, which selects its Frey-Law 2012
rates. Loads are normalized torques ``T_N`` in %MVC, constant over a step of ``dt_s``
seconds. A fatigue level of 1.0 means exhausted; the hysteresis compares it with 0.8 / 0.5.
Parameters live in ``data/fatigue.toml`` (sources in docs/sources.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Protocol

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from casadi_posture.biomech.endurance import PERCENT, EnduranceModel, Value
from casadi_posture.data import parameters
from casadi_posture.data.parameters import Parameter
from casadi_posture.errors import ProblemError

DEFAULT_RECOVERY_LAW = "threshold"
_REGION_TABLE = "fatigue.frey_law_2012."


class FatigueModel(Protocol):
    """Fatigue and recovery of n half-joints under their loads."""

    name: str

    @property
    def endurance_model(self) -> str:
        """The name of the model behind ``endurance_time_s``."""
        ...

    def initial_state(self) -> np.ndarray:
        """The rested state, shape (n,) or (n, k)."""
        ...

    def step(self, state: np.ndarray, load_pct_mvc: ArrayLike, dt_s: float) -> np.ndarray:
        """The state after ``dt_s`` [s] with each half-joint's load [%MVC] held constant."""
        ...

    def level(self, state: np.ndarray, load_pct_mvc: ArrayLike) -> np.ndarray:
        """Fatigue level per half-joint in [0, 1] (1.0 = exhausted) at the current loads [%MVC]."""
        ...

    def endurance_time_s(self, load_pct_mvc: ArrayLike, region: str) -> np.ndarray:
        """Time [s] from rest to a fatigue level of 1 under each constant load [%MVC]: the static
        endurance by the same rule as ``step`` (``inf`` where no fatigue accumulates)."""
        ...

    def endurance_expression(self, load_pct_mvc: ca.SX, region: str, value: Value) -> ca.SX | None:
        """``endurance_time_s`` [s] as a CasADi expression of a load [%MVC] at which it is
        finite, each parameter record given by ``value(record)``; None where the time is found
        by time stepping (no derivative)."""
        ...

    def rule(self) -> str:
        """One line saying when this model gives an unlimited endurance."""
        ...

    def settings(self) -> dict[str, object]:
        """The law's name and parameters, for summaries and manifests."""
        ...

    def parameters(self) -> list[Parameter]:
        """The parameter records the model uses (for ``describe``)."""
        ...


def _data(name: str) -> Parameter:
    return parameters.load("fatigue")[f"fatigue.{name}"]


def _with_user_value(parameter: Parameter, value: float | None, argument: str) -> Parameter:
    if value is None:
        return parameter
    return parameter.overridden(float(value), f"argument {argument}")


def _region_rates(regions: Sequence[str], rate: str) -> dict[str, Parameter]:
    """Frey-Law 2012 Table 1 ``rate`` (fatigue_rate / recovery_rate) of each distinct region
    (a region without data: the general one)."""
    table = parameters.load("fatigue")
    return {
        region: parameters.regional(table, _REGION_TABLE, region, rate)
        for region in dict.fromkeys(regions)
    }


def _per_half_joint(regions: Sequence[str], rates: dict[str, Parameter]) -> np.ndarray:
    return np.array([rates[region].value for region in regions], dtype=float)


def _check_time_step(dt_s: float) -> None:
    if not dt_s >= 0:
        raise ProblemError(None, "dt_s", dt_s, "a time step ≥ 0 s")


def _check_positive(value: float, key: str, expected: str) -> None:
    if not value > 0:
        raise ProblemError(None, key, value, expected)


class HoldingTimeFatigue:
    """Paper eq. 7 used incrementally, with a recovery law: ``threshold`` or ``continuous``.

    State: fatigue ``F`` per half-joint, shape (n,), rested at 0; level = ``F`` (at most 1).
    At a constant load ``T_N`` [%MVC], with ``ET`` [s] the endurance model's time, ``R_j``
    [1/s] the Frey-Law 2012 recovery rate of the region and ``r = r_rest`` (15) when the
    half-joint carries no torque (``T_N = 0``), else 1:

    - ``threshold`` (the default): above ``T_0`` ``dF/dt = 1/ET`` and no recovery; at or
      below ``T_0`` ``dF/dt = −r·R_j·F``. A group loaded above ``T_0`` never recovers.
    - ``continuous``: ``dF/dt = [T_N > T_0]/ET − r·R_j·F``, the recovery term always acting,
      so a group tires more slowly under load and may never reach exhaustion: F tends to
      ``R_∞ = 1/(ET·r·R_j)``.

    Both are linear in F over a step ``dt`` [s] and are integrated exactly. ``T_0`` (default
    15 %MVC) is what stops accumulation at small loads: Manenica's ``ET`` is finite even at
    0 %MVC.
    """

    def __init__(
        self,
        regions: Sequence[str],
        endurance: EnduranceModel,
        *,
        recovery_threshold_pct_mvc: float | None = None,
        continuous: bool = False,
    ) -> None:
        self.regions = tuple(regions)
        self.endurance = endurance
        self.name = "continuous" if continuous else "threshold"
        self._continuous = continuous
        self._endurance_parameters = endurance.parameters(self.regions)
        self._threshold = _with_user_value(
            _data("load_threshold"), recovery_threshold_pct_mvc, "load_threshold_pct_mvc"
        )
        if not self._threshold.value >= 0:
            raise ProblemError(
                None, "load_threshold_pct_mvc", self._threshold.value, "a load ≥ 0 %MVC"
            )
        self._rest_multiplier = _data("rest_multiplier")
        self._recovery_rates = _region_rates(self.regions, "recovery_rate")
        self._recovery_rate = _per_half_joint(self.regions, self._recovery_rates)

    def initial_state(self) -> np.ndarray:
        """Zero fatigue for every half-joint, shape (n,)."""
        return np.zeros(len(self.regions))

    def step(self, state: np.ndarray, load_pct_mvc: ArrayLike, dt_s: float) -> np.ndarray:
        """Fatigue after ``dt_s`` [s] at constant loads [%MVC], by the exact solution of the
        law's linear equation over the step."""
        _check_time_step(dt_s)
        fatigue = np.asarray(state, dtype=float)
        load = np.broadcast_to(np.asarray(load_pct_mvc, dtype=float), fatigue.shape)
        growth = self._growth(load)
        decay = np.where(load == 0, self._rest_multiplier.value, 1.0) * self._recovery_rate
        recovered = fatigue * np.exp(-decay * dt_s)
        if not self._continuous:
            return np.where(growth > 0, fatigue + growth * dt_s, recovered)
        settled = growth / decay
        return settled + (fatigue - settled) * np.exp(-decay * dt_s)

    def _growth(self, load: np.ndarray) -> np.ndarray:
        """``[T_N > T_0]/ET`` [1/s] of every half-joint: infinite where ``ET`` is 0 (a load
        above strength exhausts the group at once)."""
        endurance_s = np.asarray(self.endurance.endurance_time_s(load, self.regions), float)
        rate = np.divide(
            1.0, endurance_s, out=np.full_like(endurance_s, np.inf), where=endurance_s > 0
        )
        return np.where(load > self._threshold.value, rate, 0.0)

    def level(self, state: np.ndarray, load_pct_mvc: ArrayLike) -> np.ndarray:
        """The fatigue ``F`` itself (``ht/mht`` of paper eq. 7 for a constant load), at most 1:
        a step may carry ``F`` past exhaustion, which is 1."""
        return np.minimum(np.asarray(state, dtype=float), 1.0)

    def endurance_time_s(self, load_pct_mvc: ArrayLike, region: str) -> np.ndarray:
        """Time [s] from rest to F = 1 at each constant load [%MVC]: the endurance model's
        time above ``T_0`` (``threshold``), or ``−ln(1 − 1/R_∞)/(r·R_j)`` where ``R_∞ > 1``
        (``continuous``); ``inf`` where F never reaches 1."""
        load = np.asarray(load_pct_mvc, dtype=float)
        accumulates = load > self._threshold.value
        seconds = self.endurance.endurance_time_s(np.where(accumulates, load, 100.0), region)
        if not self._continuous:
            return np.where(accumulates, seconds, np.inf)
        rate = _region_rates([region], "recovery_rate")[region].value
        decay = rate * np.where(load == 0, self._rest_multiplier.value, 1.0)
        settled = np.where(accumulates, 1.0 / (seconds * decay), 0.0)
        reaches = settled > 1.0
        ratio = np.where(reaches, 1.0 / np.where(reaches, settled, 2.0), 0.5)
        return np.where(reaches, -np.log1p(-ratio) / decay, np.inf)

    def endurance_expression(self, load_pct_mvc: ca.SX, region: str, value: Value) -> ca.SX:
        """``ET`` (``threshold``) or ``−ln(1 − ET·R_j)/R_j`` (``continuous``) [s] of a loaded
        group (``T_N > T_0``)."""
        seconds = self.endurance.expression(load_pct_mvc, region, value)
        if not self._continuous:
            return seconds
        decay = value(_region_rates([region], "recovery_rate")[region])
        return -ca.log1p(-seconds * decay) / decay

    @property
    def endurance_model(self) -> str:
        """The endurance model behind ``endurance_time_s``."""
        return self.endurance.name

    def rule(self) -> str:
        """The law, its endurance model and ``T_0``."""
        text = (
            f"{self.name} recovery law, {self.endurance.name} endurance: unlimited at or "
            f"below T_0 = {self._threshold.value:g} %MVC"
        )
        if self._continuous:
            text += " and wherever recovery keeps pace (ET·R ≥ 1)"
        return text

    def settings(self) -> dict[str, object]:
        """Law, endurance model, ``T_0``, rest multiplier and recovery rates."""
        return {
            "recovery_law": self.name,
            "endurance_model": self.endurance.name,
            "load_threshold_pct_mvc": self._threshold.value,
            "rest_multiplier": self._rest_multiplier.value,
            "recovery_rate_per_s": {k: p.value for k, p in self._recovery_rates.items()},
        }

    def parameters(self) -> list[Parameter]:
        """Endurance model, ``T_0``, ``r_rest`` and ``R_j`` of the regions in use."""
        return [
            *self._endurance_parameters,
            self._threshold,
            self._rest_multiplier,
            *self._recovery_rates.values(),
        ]


def _three_compartment_rates(
    state: np.ndarray,
    target: np.ndarray,
    fatigue_rate: np.ndarray,
    recovery_rate: np.ndarray,
    development_gain: float,
    relaxation_gain: float,
) -> np.ndarray:
    """d(MA, MR, MF)/dt [%/s] of the 3CC (Xia & Frey-Law 2008), ``recovery_rate`` = r·R."""
    active, resting, fatigued = state[..., 0], state[..., 1], state[..., 2]
    gap = target - active
    drive = np.where(
        active < target,
        development_gain * np.minimum(gap, resting),
        relaxation_gain * gap,
    )
    recovered = recovery_rate * fatigued
    exhausted = fatigue_rate * active
    return np.stack([drive - exhausted, recovered - drive, exhausted - recovered], axis=-1)


class ThreeCompartmentFatigue:
    """Xia & Frey-Law 2008 three-compartment model with the 3CC-r rest multiplier (Looft 2018).

    State per half-joint: (MA, MR, MF) = active, resting, fatigued motor units [% of the pool],
    shape (n, 3), rested at (0, 100, 0). Target load ``TL = T_N`` clipped to [0, 100] %MVC
    (docs/sources.md)::

        C = L_D·(TL − MA)   if MA < TL and MR > TL − MA
            L_D·MR          if MA < TL and MR ≤ TL − MA
            L_R·(TL − MA)   if MA ≥ TL
        dMA/dt = C − F·MA,   dMR/dt = −C + r·R·MF,   dMF/dt = F·MA − r·R·MF

    ``F``, ``R`` [1/s] of the region (Frey-Law 2012 Table 1), ``L_D = L_R`` = 10 1/s, ``r = r_rest``
    (15) only while ``TL = 0``, else 1. Explicit Euler: a step ``dt`` is split into
    ``ceil(dt / max_substep_s)`` equal substeps; ``MA + MR + MF`` stays 100.

    Fatigue level = ``MF / (100 − TL)`` clipped to [0, 1] (1 when ``TL = 100``). Because
    ``MA + MR = 100 − MF`` it reaches 1 exactly when ``MA + MR = TL``: the 3CC failure point,
    where the residual capacity no longer covers the target. ``MF/100`` would not do: at
    failure it equals ``(100 − TL)/100``, below the 0.8 fatigue threshold for any load above
    20 %MVC, so the hysteresis would never fire.
    """

    name = "3cc_r"

    def __init__(self, regions: Sequence[str], *, max_substep_s: float | None = None) -> None:
        self.regions = tuple(regions)
        self._max_substep = _with_user_value(
            _data("numerics.max_substep"), max_substep_s, "max_substep_s"
        )
        _check_positive(self._max_substep.value, "max_substep_s", "a time step > 0 s")
        self._horizon = _data("numerics.endurance_horizon")
        self._development_gain = _data("three_compartment.development_gain")
        self._relaxation_gain = _data("three_compartment.relaxation_gain")
        self._rest_multiplier = _data("rest_multiplier")
        self._fatigue_rates = _region_rates(self.regions, "fatigue_rate")
        self._recovery_rates = _region_rates(self.regions, "recovery_rate")
        self._fatigue_rate = _per_half_joint(self.regions, self._fatigue_rates)
        self._recovery_rate = _per_half_joint(self.regions, self._recovery_rates)

    @property
    def max_substep_s(self) -> float:
        """Largest explicit-Euler substep [s]."""
        return float(self._max_substep.value)

    def initial_state(self) -> np.ndarray:
        """(MA, MR, MF) = (0, 100, 0) for every half-joint, shape (n, 3)."""
        state = np.zeros((len(self.regions), 3))
        state[:, 1] = PERCENT
        return state

    def _target(self, load_pct_mvc: ArrayLike) -> np.ndarray:
        return np.clip(np.asarray(load_pct_mvc, dtype=float), 0.0, PERCENT)

    def _recovery(self, target: np.ndarray, recovery_rate: np.ndarray) -> np.ndarray:
        """``r·R`` [1/s]: R multiplied by ``r_rest`` where the target load is zero."""
        return recovery_rate * np.where(target == 0, self._rest_multiplier.value, 1.0)

    def _euler(
        self,
        state: np.ndarray,
        target: np.ndarray,
        fatigue_rate: np.ndarray,
        recovery_rate: np.ndarray,
        h: float,
    ) -> np.ndarray:
        rates = _three_compartment_rates(
            state,
            target,
            fatigue_rate,
            recovery_rate,
            self._development_gain.value,
            self._relaxation_gain.value,
        )
        return state + h * rates

    def step(self, state: np.ndarray, load_pct_mvc: ArrayLike, dt_s: float) -> np.ndarray:
        """(MA, MR, MF) after ``dt_s`` [s] at constant loads [%MVC], by Euler substeps."""
        _check_time_step(dt_s)
        state = np.asarray(state, dtype=float)
        target = np.broadcast_to(self._target(load_pct_mvc), state.shape[:-1])
        recovery = self._recovery(target, self._recovery_rate)
        substeps = math.ceil(dt_s / self.max_substep_s)
        for _ in range(substeps):
            state = self._euler(state, target, self._fatigue_rate, recovery, dt_s / substeps)
        return state

    def level(self, state: np.ndarray, load_pct_mvc: ArrayLike) -> np.ndarray:
        """``MF / (100 − TL)`` clipped to [0, 1]: 1 at the 3CC failure ``MA + MR = TL``."""
        fatigued = np.asarray(state, dtype=float)[..., 2]
        capacity = PERCENT - self._target(load_pct_mvc)
        ratio = np.divide(fatigued, capacity, out=np.ones_like(fatigued), where=capacity > 0)
        return np.clip(ratio, 0.0, 1.0)

    def endurance_time_s(
        self,
        load_pct_mvc: ArrayLike,
        region: str,
        *,
        dt_s: float | None = None,
        horizon_s: float | None = None,
    ) -> np.ndarray:
        """Time [s] from rest to the 3CC failure (``MA + MR < TL``) under each constant load [%MVC].

        Explicit Euler with step ``dt_s`` (default ``max_substep_s``), first step count at
        which the failure holds, up to ``horizon_s`` (default
        ``fatigue.numerics.endurance_horizon``). Beyond it, the sustained phase (MA = TL) has
        the closed form ``MF(t) = (F·TL/R)(1 − exp(−R·t))``, which reaches ``100 − TL`` at
        ``t = −ln(1 − R·(100 − TL)/(F·TL))/R`` (within 1 % of Euler: it leaves out the
        seconds-long transients of MA). ``inf`` for
        loads at or below the sustainable level ``100·R/(R + F)``, where
        ``MF ≤ F·TL/R ≤ 100 − TL`` for ever.
        """
        dt = self.max_substep_s if dt_s is None else dt_s
        horizon = self._horizon.value if horizon_s is None else horizon_s
        _check_positive(dt, "dt_s", "a time step > 0 s")
        fatigue_rate = _region_rates([region], "fatigue_rate")[region].value
        recovery_rate = _region_rates([region], "recovery_rate")[region].value
        load = np.asarray(load_pct_mvc, dtype=float)
        target = self._target(load).ravel()
        times = np.full(target.shape, np.inf)
        running = target > PERCENT * recovery_rate / (recovery_rate + fatigue_rate)
        state = np.tile([0.0, PERCENT, 0.0], (target.size, 1))
        fatigue = np.full(target.shape, fatigue_rate)
        recovery = self._recovery(target, np.full(target.shape, recovery_rate))
        steps = 0
        while running.any() and (steps + 1) * dt <= horizon:
            state = self._euler(state, target, fatigue, recovery, dt)
            steps += 1
            failed = running & (state[:, 0] + state[:, 1] < target)
            times[failed] = steps * dt
            running &= ~failed
        ratio = recovery_rate * (PERCENT - target[running]) / (fatigue_rate * target[running])
        times[running] = np.maximum(-np.log1p(-ratio) / recovery_rate, horizon)
        return times.reshape(load.shape)

    def endurance_expression(self, load_pct_mvc: ca.SX, region: str, value: Value) -> None:
        """None: the 3CC time to failure is found by time stepping (``endurance_time_s``)."""
        return None

    @property
    def endurance_model(self) -> str:
        """Its own: the 3CC time to failure (``endurance_time_s``), whatever
        ``fatigue.endurance`` says."""
        return self.name

    def rule(self) -> str:
        """``3cc_r`` and its sustainable loads."""
        levels = ", ".join(
            f"{region} {PERCENT * r / (r + f):.1f}"
            for region, r, f in zip(
                self._recovery_rates,
                (p.value for p in self._recovery_rates.values()),
                (p.value for p in self._fatigue_rates.values()),
                strict=True,
            )
        )
        return f"3cc_r recovery law: unlimited at or below the sustainable load ({levels} %MVC)"

    def settings(self) -> dict[str, object]:
        """The law, its rest multiplier and the fatigue and recovery rates per region."""
        return {
            "recovery_law": self.name,
            "rest_multiplier": self._rest_multiplier.value,
            "fatigue_rate_per_s": {k: p.value for k, p in self._fatigue_rates.items()},
            "recovery_rate_per_s": {k: p.value for k, p in self._recovery_rates.items()},
        }

    def parameters(self) -> list[Parameter]:
        """Gains, ``r_rest``, ``F`` and ``R`` of the regions in use, and the Euler substep."""
        return [
            self._development_gain,
            self._relaxation_gain,
            self._rest_multiplier,
            *self._fatigue_rates.values(),
            *self._recovery_rates.values(),
            self._max_substep,
        ]


def _threshold(
    regions: Sequence[str], endurance: EnduranceModel, load_threshold_pct_mvc: float | None
) -> FatigueModel:
    return HoldingTimeFatigue(regions, endurance, recovery_threshold_pct_mvc=load_threshold_pct_mvc)


def _continuous(
    regions: Sequence[str], endurance: EnduranceModel, load_threshold_pct_mvc: float | None
) -> FatigueModel:
    return HoldingTimeFatigue(
        regions, endurance, recovery_threshold_pct_mvc=load_threshold_pct_mvc, continuous=True
    )


def _three_compartment(
    regions: Sequence[str], endurance: EnduranceModel, load_threshold_pct_mvc: float | None
) -> FatigueModel:
    if load_threshold_pct_mvc is not None:
        expected = "no load threshold with the 3cc_r law (its recovery never stops)"
        raise ProblemError(None, "load_threshold_pct_mvc", load_threshold_pct_mvc, expected)
    return ThreeCompartmentFatigue(regions)


RECOVERY_LAWS: dict[str, Callable[[Sequence[str], EnduranceModel, float | None], FatigueModel]] = {
    "threshold": _threshold,
    "continuous": _continuous,
    "3cc_r": _three_compartment,
}


def fatigue_model(
    name: str,
    *,
    regions: Sequence[str],
    endurance: EnduranceModel,
    recovery_threshold_pct_mvc: float | None = None,
) -> FatigueModel:
    """The fatigue model of recovery law ``name`` (a key of ``RECOVERY_LAWS``).

    ``regions[i]`` is the joint region of half-joint i. ``endurance`` drives ``threshold``
    and ``continuous``; ``3cc_r`` has its own endurance
    (``ThreeCompartmentFatigue.endurance_time_s``) and ignores it.
    ``recovery_threshold_pct_mvc`` overrides ``T_0`` of the first two [%MVC].
    """
    if name not in RECOVERY_LAWS:
        raise ProblemError(None, "fatigue.recovery_law", name, f"one of {', '.join(RECOVERY_LAWS)}")
    return RECOVERY_LAWS[name](regions, endurance, recovery_threshold_pct_mvc)
