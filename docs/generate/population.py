"""The population runs of docs/population.md, each made once per check in the background
(40 workers each: too slow to run while the page is made), and the ANSUR II model the
workers are drawn from.

``population run=NAME`` is the console block of one of :data:`COMMANDS` (its text must be
the command's; ``keep=`` and ``cut=`` as for ``console``; the figure the page shows is
made by docs/generate/figures.py); ``population-facts`` gives the values of the prose
beside them, ``ansur-table`` writes the table of the sampling model and ``ansur`` gives
its values."""

from __future__ import annotations

import csv
import io
import json
import math
import re
import shlex
import statistics
from statistics import NormalDist
from typing import Any

from casadi_posture.biomech.capability import population_cv
from casadi_posture.people import sampling
from casadi_posture.people.statistics import wilson

from . import console, parallel
from .regions import Region
from .runs import listed
from .session import Session

#: The page's runs by name: the words after ``casadi-posture``, and the folder they write.
COMMANDS = {
    "wall": (
        "population problems/standing_wall_horizontal.toml --n 20 --jobs 2",
        "out/population/standing_wall_horizontal",
    ),
    "schedule": (
        "population problems/standing_wall_horizontal.toml --n 20 --jobs 2 "
        "--set schedule.t_on_s=60 --set schedule.t_off_s=30 --out out/population/wall-60-30",
        "out/population/wall-60-30",
    ),
    "shelf": (
        "population problems/standing_shelf_box.toml --n 20 --jobs 2",
        "out/population/standing_shelf_box",
    ),
}
CASES = [(name,) for name in COMMANDS]
#: ANSUR II's body mass percentiles P5 / P50 / P95 [kg] by sex, from the survey's raw
#: data (as tests/test_population.py quotes them): what the lognormal model is held to.
SURVEY_MASS_KG = {"male": (64.4, 84.6, 110.7), "female": (51.3, 66.8, 87.1)}
SEXES = ("male", "female")


def run(name: str) -> dict[str, Any]:
    """One of :data:`COMMANDS` run in a fresh copy of ``problems/``: ``output`` (what it
    prints), ``summary`` (population.json) and ``rows`` (summary.csv's rows)."""
    command, out = COMMANDS[name]
    session = Session()
    try:
        output = console.run([f"$ casadi-posture {command}"], session)
        folder = session.folder / out
        with (folder / "summary.csv").open(newline="") as handle:
            rows = list(csv.DictReader(handle))
        return {
            "output": output,
            "summary": json.loads((folder / "population.json").read_text()),
            "rows": rows,
        }
    finally:
        session.close()


def prefetch() -> None:
    """Start every run in the background."""
    parallel.submit(run, CASES)


def all_runs() -> dict[str, dict[str, Any]]:
    """:func:`run` of every command, by name."""
    return {name: found for (name,), found in parallel.compute(run, CASES).items()}


def block(region: Region, session: Session) -> str:
    """The console block of the run ``run=``, as the command prints it today."""
    name = region.args["run"]
    fence, found = console.commands(region.body)
    written = " ".join(shlex.split(" ".join(line.removesuffix("\\") for line in found[0]))[1:])
    if len(found) != 1 or written != f"casadi-posture {COMMANDS[name][0]}":
        raise ValueError(f"the block's command is not run {name!r}'s: {COMMANDS[name][0]}")
    made = all_runs()[name]
    printed = console.shorten(made["output"], region.args.get("keep"), region.args.get("cut"))
    return "\n".join([fence, *found[0], *printed, "```"])


def seconds(rows: list[dict[str, str]], column: str = "task_held_s") -> list[float]:
    """A column of summary.csv's rows, as numbers (the empty cells left out)."""
    return [float(r[column]) for r in rows if r[column] != ""]


#: The flags a worker's run may carry, as the prose counts them: a pattern of its text in
#: summary.csv's ``flags``, and the words after the count of workers.
REASONS = (
    (r"over strength at the start", "over strength at the start"),
    (r"(\d+) steps where neither IK solver converged", "with {} steps no IK solver converged on"),
    (r"low-back compression", "with the L5/S1 compression above the NIOSH design limit"),
    (r"held asymmetrically", "holding the mirror-symmetric task asymmetrically"),
    (r"trunk twisted or bent sideways", "with the trunk twisted or bent sideways"),
    (r"rests on its", "with a joint at the end of its range for a minute or more"),
)


def reasons(rows: list[dict[str, str]]) -> str:
    """How many of the workers' runs carry each flag of :data:`REASONS` ('3 over strength
    at the start and 1 with 39 steps no IK solver converged on'; 'none' when no run is
    flagged); a flagged run with none of them is counted as 'with another flag'."""
    counts: dict[str, int] = {}
    for row in filter(lambda r: r["flags"], rows):
        labels = [
            words.format(*found.groups())
            for pattern, words in REASONS
            if (found := re.search(pattern, row["flags"]))
        ] or ["with another flag"]
        for label in labels:
            counts[label] = counts.get(label, 0) + 1
    return listed([f"{n} {label}" for label, n in counts.items()]) if counts else "none"


def sex_facts(found: dict[str, Any], sex: str) -> dict[str, Any]:
    """What the prose says of one sex in one run: its population.json entry, ``held``
    (the count still holding at each minute of the summary), ``median_min``, ``at_end``
    (the count who held to the end of the run), ``not_sustainable``, ``over`` (the workers
    over strength at the start: their ``count``, the ``groups`` over strength, and the
    least and most ``load_min``/``load_max`` [%MVC] of their most loaded group), ``others``
    (the other workers' longest and median time held [s]) and ``reasons``
    (:func:`reasons`)."""
    entry = found["summary"]["sexes"][sex]
    rows = [r for r in found["rows"] if r["body.sex"] == sex]
    over = [r for r in rows if r["over_strength_at_start"] not in ("", "[]")]
    loads = [
        max(float(v) for k, v in r.items() if k.startswith("initial_load_") and v != "")
        for r in over
    ]
    groups = {g.rsplit("_", 1)[0] for r in over for g in r["over_strength_at_start"].split("+")}
    others = seconds([r for r in rows if r not in over])
    return entry | {
        "held": {s["minutes"]: s["held"] for s in entry["still_holding"]},
        "median_min": entry["median_task_held_s"] / 60,
        "at_end": sum(r["task_held_is_lower_bound"] == "True" for r in rows),
        "not_sustainable": entry["sustainable"]["n"] - entry["sustainable"]["count"],
        "over": {
            "count": len(over),
            "groups": listed(sorted(g.replace("_", " ") for g in groups)) if groups else "",
            "load_min": min(loads, default=math.nan),
            "load_max": max(loads, default=math.nan),
        },
        "others": {
            "max_s": max(others, default=math.nan),
            "median_s": statistics.median(others) if others else math.nan,
        },
        "reasons": reasons(rows),
    }


def facts(region: Region, session: Session) -> dict[str, Any]:
    """Every run's values by name and sex (``{shelf[female][over][count]}``), with its
    ``n`` per sex and ``horizon_min`` [min]; and ``pm_points``, the half-width [percentage points]
    of the 95 % interval of a share of one half among ``n`` workers of the wall run."""
    found: dict[str, Any] = {}
    for name, made in all_runs().items():
        n = made["summary"]["n_per_sex"]
        found[name] = {sex: sex_facts(made, sex) for sex in SEXES} | {
            "n": n,
            "horizon_min": made["summary"]["horizon_s"] / 60,
        }
    n = found["wall"]["n"]
    low, high = wilson(n // 2, n)
    return found | {"pm_points": 100 * (high - low) / 2}


def model(sex: str) -> dict[str, Any]:
    """The sampling model of one sex (data/population.toml): ``a`` (its anthropometry),
    the lognormal mass's ``mass_mean``, ``mass_sd`` and ``mass_pct`` (P5, P50, P95)
    [kg], ``survey_pct`` (the survey's), ``off_kg`` (the largest difference between the
    two), ``normal_p5_low_kg`` (how far below the survey's P5 a normal mass of the same
    mean and SD puts it) and the age's ``age_mean``, ``age_sd``, ``age_median``,
    ``age_first`` and ``age_last`` [years]."""
    a = sampling.anthropometry(sex)
    mu, s = a["log_mass_mean"], a["log_mass_sd"]
    z = NormalDist().inv_cdf(0.95)
    mass_pct = [math.exp(mu + k * z * s) for k in (-1, 0, 1)]
    mean = math.exp(mu + s * s / 2)
    sd = mean * math.sqrt(math.exp(s * s) - 1)
    first, share = sampling.ages(sex)
    years = [first + i for i in range(share.size)]
    age_mean = sum(y * p for y, p in zip(years, share, strict=True))
    age_sd = math.sqrt(sum((y - age_mean) ** 2 * p for y, p in zip(years, share, strict=True)))
    cumulative = [sum(share[: i + 1]) for i in range(share.size)]
    survey = SURVEY_MASS_KG[sex]
    return {
        "a": a,
        "mass_mean": mean,
        "mass_sd": sd,
        "mass_pct": mass_pct,
        "survey_pct": survey,
        "off_kg": max(abs(m - p) for m, p in zip(mass_pct, survey, strict=True)),
        "normal_p5_low_kg": survey[0] - (mean - z * sd),
        "age_mean": age_mean,
        "age_sd": age_sd,
        "age_median": next(y for y, c in zip(years, cumulative, strict=True) if c >= 0.5),
        "age_first": years[0],
        "age_last": max(y for y, p in zip(years, share, strict=True) if p > 0),
    }


def ansur(region: Region, session: Session) -> dict[str, Any]:
    """:func:`model` of each sex, ``off_kg`` and ``normal_p5_low_kg`` the larger of the
    two sexes', ``group_correlation`` and ``cv`` (the strength spread where no population
    SD is known)."""
    found: dict[str, Any] = {sex: model(sex) for sex in SEXES}
    return found | {
        "off_kg": max(found[s]["off_kg"] for s in SEXES),
        "normal_p5_low_kg": max(found[s]["normal_p5_low_kg"] for s in SEXES),
        "group_correlation": sampling.group_correlation(),
        "cv": float(population_cv().value),
    }


def ansur_table(region: Region, session: Session) -> str:
    """The table of the sampling model, men and women."""
    m = {sex: model(sex) for sex in SEXES}
    rows: list[tuple[str, ...]] = [
        (
            "stature [m], normal",
            *(f"{m[s]['a']['stature_mean']:.4f} ± {m[s]['a']['stature_sd']:.4f}" for s in SEXES),
        ),
        (
            "body mass [kg], lognormal: ln mass",
            *(
                f"{m[s]['a']['log_mass_mean']:.5f} ± {m[s]['a']['log_mass_sd']:.5f} "
                f"({m[s]['mass_mean']:.1f} ± {m[s]['mass_sd']:.1f} kg)"
                for s in SEXES
            ),
        ),
        (
            "mass P5 / P50 / P95 [kg], lognormal",
            *(" / ".join(f"{v:.1f}" for v in m[s]["mass_pct"]) for s in SEXES),
        ),
        (
            "mass P5 / P50 / P95 [kg], survey",
            *(" / ".join(f"{v:.1f}" for v in m[s]["survey_pct"]) for s in SEXES),
        ),
        (
            "correlation of stature with ln mass",
            *(f"{m[s]['a']['correlation']:.3f}" for s in SEXES),
        ),
        (
            f"age [years], the survey's own distribution ({m['male']['age_first']} and over)",
            *(
                f"{m[s]['age_mean']:.1f} ± {m[s]['age_sd']:.1f}, median {m[s]['age_median']} "
                f"({m[s]['age_first']} to {m[s]['age_last']})"
                for s in SEXES
            ),
        ),
        (
            "normal-score correlation of age with stature / with ln mass",
            *(
                f"{m[s]['a']['stature_age_correlation']:.3f} / "
                f"{m[s]['a']['log_mass_age_correlation']:.3f}".replace("-", "−")
                for s in SEXES
            ),
        ),
    ]
    out = io.StringIO()
    out.write("| | men | women |\n|---|---|---|\n")
    for row in rows:
        out.write("| " + " | ".join(row) + " |\n")
    return out.getvalue()
