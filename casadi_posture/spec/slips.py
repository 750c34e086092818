"""Slips a valid problem may hold: values each in range for its key that together most
likely mean another unit, or two things swapped (thresholds in data/slips.toml). Each one
found is a note, printed as ``note:`` by every command that loads the problem and carried in
its JSON and summary.json, never an error: the input may be what was meant (docs/answers.md).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

from casadi_posture.data import parameters
from casadi_posture.spec.schema import BodySpec, LoadSpec, PositionTask, ProblemSpec, Task
from casadi_posture.spec.sides import sided_pairs

#: One pound [kg] (exact, by definition).
POUND_KG = 0.45359237


def _value(name: str) -> float:
    return float(parameters.value("slips", name))


def problem_notes(spec: ProblemSpec, path: Path) -> tuple[str, ...]:
    """The notes of a validated problem's data (``path`` names it): its body's mass index,
    its loads' masses, its hands' targets and its ``posture_deg``."""
    found = [
        bmi_note(spec.body, path),
        *load_notes(spec.loads, path),
        *crossed_targets_notes(spec.tasks, path),
        radians_note(spec.posture_deg, "posture_deg", path),
    ]
    return tuple(note for note in found if note is not None)


def bmi_note(body: BodySpec, path: Path) -> str | None:
    """A note when the body mass index, ``body.mass_kg`` / ``body.stature_m``² [kg/m²], lies
    outside ``bmi.lowest``–``bmi.highest``: the masses inside at this stature, and, when the
    mass read as pounds is one of them, that slip. (A stature in cm is refused already: it is
    over 2.5 m.)"""
    lowest, highest = _value("bmi.lowest"), _value("bmi.highest")
    mass, area = body.mass_kg, body.stature_m**2
    bmi = mass / area
    if lowest <= bmi <= highest:
        return None
    note = (
        f"{path}: body.mass_kg = {mass:g} at body.stature_m = {body.stature_m:g} is a body "
        f"mass index of {bmi:.1f} kg/m², outside {lowest:g}–{highest:g} (at "
        f"{body.stature_m:g} m: {lowest * area:.1f}–{highest * area:.1f} kg)"
    )
    pounds = mass * POUND_KG
    if lowest <= pounds / area <= highest:
        note += f"; a mass in pounds? {mass:g} lb = {pounds:.1f} kg, BMI {pounds / area:.1f}"
    return note


def load_notes(loads: Sequence[LoadSpec], path: Path) -> list[str]:
    """A unit hint per load heavier than ``load.heaviest`` [kg]: grams, or pounds when the
    mass in pounds is within it?"""
    heaviest = _value("load.heaviest")
    notes = []
    for i, load in enumerate(loads):
        if load.mass_kg <= heaviest:
            continue
        pounds = load.mass_kg * POUND_KG
        hint = f" or in pounds ({pounds:.1f} kg)" if pounds <= heaviest else ""
        notes.append(
            f"{path}: loads[{i}].mass_kg = {load.mass_kg:g}: over {heaviest:g} kg, more than "
            f"a person holds; a mass in grams ({load.mass_kg / 1000:g} kg){hint}?"
        )
    return notes


def crossed_targets_notes(tasks: Sequence[Task], path: Path) -> list[str]:
    """A note per pair of hands (effectors ``X_r`` and ``X_l`` with a position task each)
    whose left target lies to the right of the right one by more than the plausibility
    report's ``crossed_hands`` margin: the arms would cross, the targets swapped? Right and
    left are along the world's y (the subject's left): the body's base, its feet on the floor
    or its pelvis on a seat, is fixed in the world facing x (docs/problem-files.md)."""
    margin = float(parameters.value("plausibility", "crossed_hands"))
    targets = {
        t.effector: (i, t.target_m) for i, t in enumerate(tasks) if isinstance(t, PositionTask)
    }
    notes = []
    for right, left in sided_pairs(targets):
        (i, on_right), (j, on_left) = targets[right], targets[left]
        crossing = on_right[1] - on_left[1]
        if crossing > margin:
            notes.append(
                f"{path}: tasks[{j}].target_m (the {left} target) lies {crossing:.2f} m to the "
                f"right of tasks[{i}].target_m (the {right} target): the arms would cross; "
                "the two targets swapped? (y points to the subject's left)"
            )
    return notes


def radians_note(degrees: Mapping[str, float], key: str, path: Path) -> str | None:
    """A note when angles given in degrees (``key``: ``posture_deg`` or ``--posture``) all
    look like radians: every one within ±``radians.largest`` (π rounded up: a posture in
    radians has every angle within ±π), at least one non-zero, and either two or more
    non-zero or one not a whole number. Typed in degrees, a posture whose every angle is
    within 3.2° of zero moves at most one joint a little, and by a whole number of degrees
    (``elbow_flexion=2``); radians of a real posture are seldom whole. A single whole
    value (``=1``, ``=3``) is therefore taken at its word, a slip left unnoted."""
    largest = _value("radians.largest")
    moved = [v for v in degrees.values() if v != 0.0]
    if not moved or any(abs(v) > largest for v in degrees.values()):
        return None
    if len(moved) == 1 and float(moved[0]).is_integer():
        return None
    given = ", ".join(f"{name} = {v:g}" for name, v in degrees.items())
    meant = ", ".join(f"{name}={math.degrees(v):.1f}" for name, v in degrees.items())
    verb = "looks" if len(degrees) == 1 else "look"
    return (
        f"{path}: {key} {given} {verb} like radians (every angle within ±{largest:g}): read "
        f"as degrees; radians meant? in degrees that is {meant}"
    )
