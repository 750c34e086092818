"""Slips caught as notes (spec/slips.py): a body mass in pounds, angles in radians, the hands'
targets swapped, a load in grams; each in every command that loads the problem, in the JSON
and summary.json, with the exit code unchanged; none on a shipped problem or template."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

from casadi_posture import api
from casadi_posture.cli import main
from casadi_posture.data.templates import TEMPLATES, template
from casadi_posture.output.results import summary
from casadi_posture.problem import load_problem
from casadi_posture.spec.slips import radians_note

SHELF = PROBLEMS / "standing_shelf_box.toml"
HOLD = PROBLEMS / "holding_m45.toml"

#: A 1.60 m woman whose 60 kg were written in pounds: 132 lb.
IN_POUNDS = ("--set=body.sex=female", "--set=body.stature_m=1.60", "--set=body.mass_kg=132")
#: The shelf's hands' targets swapped: the left hand's 0.15 m to the right, and the right's left.
SWAPPED = {"tasks[2].target_m": [0.62, 0.15, 1.40], "tasks[3].target_m": [0.62, -0.15, 1.40]}


def run(*args: str):
    return CliRunner().invoke(main, [str(a) for a in args])


def notes(stdout: str) -> list[str]:
    return [line for line in stdout.splitlines() if line.startswith("note: ")]


def test_a_body_mass_in_pounds_is_noted_with_its_bmi_and_the_kilograms() -> None:
    result = run("validate", SHELF, *IN_POUNDS)
    assert result.exit_code == 0, result.output
    # By hand: 132 / 1.6² = 51.56 kg/m²; 132 lb × 0.45359237 = 59.87 kg, / 1.6² = 23.39.
    assert notes(result.stdout) == [
        f"note: {SHELF}: body.mass_kg = 132 at body.stature_m = 1.6 is a body mass index of "
        "51.6 kg/m², outside 15–45 (at 1.6 m: 38.4–115.2 kg); a mass in pounds? "
        "132 lb = 59.9 kg, BMI 23.4"
    ]


def test_a_light_body_for_its_stature_is_noted_without_pounds() -> None:
    problem = load_problem(SHELF, {"body.stature_m": 2.0, "body.mass_kg": 50.0})
    # 50 / 2² = 12.5 kg/m², below 15; in pounds it would be lighter still.
    (note,) = problem.notes
    assert "body mass index of 12.5 kg/m²" in note and "(at 2 m: 60.0–180.0 kg)" in note
    assert "pounds" not in note


def test_radians_given_to_posture_are_noted_in_the_degrees_they_would_be() -> None:
    result = run("torques", SHELF, "--posture", "shoulder_flexion_r=1.57")
    # Flagged as before: the right arm down (1.57°) and the left at 60° on a symmetric task.
    assert result.exit_code == 1 and "held asymmetrically" in result.stdout
    # 1.57 rad × 180/π = 89.95°.
    assert notes(result.stdout)[0] == (
        f"note: {SHELF}: --posture shoulder_flexion_r = 1.57 looks like radians (every angle "
        "within ±3.2): read as degrees; radians meant? in degrees that is shoulder_flexion_r=90.0"
    )
    # Read as given, in degrees: 60° on the left - 1.57° = 58.43° apart.
    assert "(shoulder_flexion_r 58.4° from its mirror" in result.stdout


@pytest.mark.parametrize(
    ("degrees", "noted"),
    [
        ({"a": 1.57}, True),  # not a whole number: radians
        ({"a": 0.5, "b": -1.2}, True),
        ({"a": 1.0, "b": 2.0}, True),  # two joints moved, each within 3.2: radians
        ({"a": 0.0, "b": 1.0, "c": 0.0}, False),  # one joint nudged a whole degree
        ({"a": 3.0}, False),
        ({"a": 0.0, "b": 0.0}, False),  # the zero posture, in either unit
        ({"a": 1.57, "b": 45.0}, False),  # 45 is no angle in radians
        ({"a": 3.3, "b": 1.2}, False),  # beyond π: not radians
    ],
)
def test_the_radians_rule(degrees: dict[str, float], noted: bool) -> None:
    assert (radians_note(degrees, "--posture", Path("p.toml")) is not None) is noted


def test_swapped_hand_targets_are_noted_when_loaded() -> None:
    sets = [f"--set={key}={value}" for key, value in SWAPPED.items()]
    result = run("validate", SHELF, *sets)
    assert result.exit_code == 0, result.output
    # The right hand's target at y = +0.15 m (left), the left's at -0.15 m: 0.30 m crossed.
    assert notes(result.stdout) == [
        f"note: {SHELF}: tasks[3].target_m (the grip_l target) lies 0.30 m to the right of "
        "tasks[2].target_m (the grip_r target): the arms would cross; the two targets swapped? "
        "(y points to the subject's left)"
    ]


def test_a_load_in_grams_gets_a_unit_hint() -> None:
    result = run("validate", HOLD, "--set", "loads[0].mass_kg=500")
    assert result.exit_code == 0, result.output
    assert notes(result.stdout) == [
        f"note: {HOLD}: loads[0].mass_kg = 500: over 100 kg, more than a person holds; a mass "
        "in grams (0.5 kg)?"
    ]
    # 150 lb = 68.0 kg: within 100 kg, so pounds is a hint too.
    (note,) = load_problem(HOLD, {"loads[0].mass_kg": 150.0}).notes
    assert note.endswith("a mass in grams (0.15 kg) or in pounds (68.0 kg)?")


def test_under_json_the_notes_are_in_the_json_and_on_stderr() -> None:
    result = run("torques", HOLD, "--set", "loads[0].mass_kg=500", "--json")
    data = json.loads(result.stdout)  # stdout is the JSON alone
    assert result.exit_code == 1  # over strength, as without the note
    assert len(data["notes"]) == 1 and "loads[0].mass_kg = 500" in data["notes"][0]
    assert result.stderr == f"note: {data['notes'][0]}\n"
    described = json.loads(run("describe", HOLD, *IN_POUNDS, "--json").stdout)
    assert "BMI 23.4" in described["notes"][0]


def test_the_solved_answer_and_a_run_carry_the_notes() -> None:
    solved = json.loads(run("solve", HOLD, "--set", "body.mass_kg=150", "--json").stdout)
    assert "body mass index of 49.5 kg/m²" in solved["notes"][0]  # 150 / 1.741² = 49.49
    heavy = load_problem(HOLD, {"loads[0].mass_kg": 150.0, "simulation.duration_s": 2.0})
    report = summary(api.simulate(heavy).result)
    assert report["notes"] == list(heavy.notes) and len(report["notes"]) == 1


def test_whatif_rows_carry_each_case_s_notes(tmp_path: Path) -> None:
    result = run(
        "whatif", HOLD, "--static", "--vary", "loads[0].mass_kg=2,150", "--out", tmp_path / "w"
    )
    assert result.exit_code == 1, result.output  # 150 kg is over strength
    with (tmp_path / "w" / "summary.csv").open(encoding="utf-8") as table:
        rows = {float(r["loads[0].mass_kg"]): r for r in csv.DictReader(table)}
    assert rows[2.0]["notes"] == ""
    assert "loads[0].mass_kg = 150" in rows[150.0]["notes"]
    assert f"note: case {rows[150.0]['case']}: {rows[150.0]['notes']}" in result.stdout


def test_no_shipped_problem_or_template_holds_a_slip() -> None:
    for path in sorted(PROBLEMS.glob("*.toml")):
        assert load_problem(path).notes == (), path
    for name in TEMPLATES:
        assert load_problem(f"{name}.toml", text=template(name)).notes == (), name
    result = run("validate", PROBLEMS)
    assert result.exit_code == 0 and notes(result.stdout) == []


#: Each command that writes a JSON result beside its other files: its options (short runs)
#: and the JSON file; population's with a note every worker shares.
WRITERS = {
    "design": (["--free", "tasks[0].point_m[2],tasks[1].target_m[2]=-0.5:0.1"], "design.json"),
    "duty-cycle": (["--t-off", "30", "--horizon", "60"], "duty_cycle.json"),
    "sensitivity": ([], "sensitivity.json"),
    "population": (
        ["--n", "1", "--sex", "male", "--jobs", "1", "--set", "simulation.duration_s=5"],
        "population.json",
    ),
}


def written_notes(command: str, out: Path, *sets: str) -> tuple[list[str], str]:
    """The notes of the JSON file ``command`` writes into ``out``, and what it printed."""
    options, name = WRITERS[command]
    result = run(command, HOLD, *options, *sets, "--out", out)
    assert result.exit_code in (0, 1), result.output  # no bad input, no crash
    data = json.loads((out / name).read_text(encoding="utf-8"))
    held = data if isinstance(data, dict) else data[0]  # duty-cycle: a search per rest
    return held["notes"], result.stdout


@pytest.mark.parametrize("command", list(WRITERS))
def test_every_json_file_carries_the_problem_s_notes(command: str, tmp_path: Path) -> None:
    notes, stdout = written_notes(command, tmp_path / "out", "--set", "loads[0].mass_kg=500")
    slip = next(note for note in notes if "loads[0].mass_kg = 500" in note)
    assert slip.endswith("over 100 kg, more than a person holds; a mass in grams (0.5 kg)?")
    assert stdout.count(f"note: {slip}\n") == 1  # printed once, as written


@pytest.mark.parametrize("command", list(WRITERS))
def test_a_problem_without_a_slip_writes_no_note(command: str, tmp_path: Path) -> None:
    notes, stdout = written_notes(command, tmp_path / "out")
    # Every slip's note starts with the file; design.json keeps the design's own notes.
    assert not [note for note in notes if note.startswith(f"{HOLD}: ")]
    assert notes == [] or command == "design"
    assert f"note: {HOLD}: " not in stdout
