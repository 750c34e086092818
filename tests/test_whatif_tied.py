"""What-if axes of tied keys (``--vary 'KEY1,KEY2=...'``: both hands' heights, both halves of
a load) and the figures of a multi-key grid: one per answer, against the first axis."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

import casadi_posture as cp
from casadi_posture.cli import main
from casadi_posture.output.axes import axis_label
from casadi_posture.problem import load_problem
from casadi_posture.runs import whatif_plots
from casadi_posture.runs.whatif import grid

SHELF = PROBLEMS / "standing_shelf_box.toml"
HOLD = PROBLEMS / "holding_m45.toml"
HEIGHTS = "tasks[2].target_m[2],tasks[3].target_m[2]"
HALVES = "loads[0].mass_kg,loads[1].mass_kg"


def _endurance_min(overrides: dict[str, float | str]) -> float:
    """The limiting group's endurance at the start [min], solved on its own."""
    answer = cp.solve(cp.load(SHELF if "loads[1].mass_kg" in overrides else HOLD, overrides))
    return answer.limiting.endurance_s / 60


def test_tied_keys_give_both_keys_each_value_and_the_answer_of_that_problem(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Each case sets both hands' heights and both halves of the box to one value; its
    answer is the one of the problem with those four values set by hand, and differs from
    one with a single hand moved (so a tie that set one key only would fail)."""
    drawn: list[tuple[str, str, list[str]]] = []
    save = whatif_plots.save_figure

    def record(fig, path):  # the axis titles and legend of every figure drawn
        ax = fig.axes[0]
        legend = [t.get_text() for t in ax.get_legend().get_texts()]
        drawn.append((ax.get_xlabel(), ax.get_ylabel(), legend))
        return save(fig, path)

    monkeypatch.setattr(whatif_plots, "save_figure", record)
    vary = {HEIGHTS: [1.2, 1.4], HALVES: [2.0, 4.0]}
    report = cp.whatif(SHELF, vary, tmp_path / "w", static=True)
    rows = report.rows
    assert len(rows) == 4
    pairs = {(r["tasks[2].target_m[2]"], r["loads[0].mass_kg"]) for r in rows}
    assert pairs == set(itertools.product([1.2, 1.4], [2.0, 4.0]))
    for row in rows:
        assert row["tasks[2].target_m[2]"] == row["tasks[3].target_m[2]"]
        assert row["loads[0].mass_kg"] == row["loads[1].mass_kg"]
    row = next(r for r in rows if r["tasks[2].target_m[2]"] == 1.2 and r["loads[0].mass_kg"] == 4)
    both = {"tasks[2].target_m[2]": 1.2, "tasks[3].target_m[2]": 1.2}
    halves = {"loads[0].mass_kg": 4.0, "loads[1].mass_kg": 4.0}
    alone = _endurance_min(both | halves)
    assert row["limiting_endurance_at_start_min"] == pytest.approx(alone, rel=1e-6)
    one_hand = _endurance_min({"tasks[2].target_m[2]": 1.2} | halves)
    assert abs(one_hand - alone) > 0.005
    # one figure per answer (the static ones the rows carry), all against the first axis,
    # named in words with its unit; one line per value of the other axis
    carried = [
        o
        for o in whatif_plots.STATIC_OUTCOMES
        if any(r.get(c) is not None for r in rows for c in whatif_plots.SERIES.get(o, [o]))
    ]
    assert len(report.figures) == len(carried) >= 4
    assert all(p.name.endswith("_vs_tasks_2_.target_m_2.png") for p in report.figures)
    assert {x for x, _, _ in drawn} == {"right/left hand at shelf height (m)"}
    rula = next(legend for _, y, legend in drawn if y == whatif_plots.OUTCOMES["worst_rula"])
    assert rula[:2] == ["box right/left half mass = 2 kg", "box right/left half mass = 4 kg"]


def test_a_tied_axis_counts_as_one_in_a_grid_and_in_a_paired_study() -> None:
    """Three heights tied × two sexes: 6 cases, each with both heights equal; paired: 2."""
    full = grid(
        str(SHELF),
        [(HEIGHTS, [1.0, 1.2, 1.4]), ("body.sex", ["male", "female"])],
        solver=None,
        simulate=False,
    )
    assert len(full) == 6
    chosen = {(c.overrides["tasks[3].target_m[2]"], c.overrides["body.sex"]) for c in full}
    assert chosen == set(itertools.product([1.0, 1.2, 1.4], ["male", "female"]))
    assert all(
        c.overrides["tasks[2].target_m[2]"] == c.overrides["tasks[3].target_m[2]"] for c in full
    )
    paired = grid(
        str(SHELF),
        [(HEIGHTS, [1.0, 1.4]), ("body.sex", ["female", "male"])],
        solver=None,
        simulate=False,
        paired=True,
    )
    assert [(c.overrides["tasks[3].target_m[2]"], c.overrides["body.sex"]) for c in paired] == [
        (1.0, "female"),
        (1.4, "male"),
    ]


def test_axes_are_named_in_words() -> None:
    data = load_problem(SHELF).data
    assert axis_label(data, HEIGHTS) == ("right/left hand at shelf height", "m")
    assert axis_label(data, HALVES) == ("box right/left half mass", "kg")
    assert axis_label(data, "tasks[2].target_m[0]") == ("right hand at shelf distance forward", "m")
    assert axis_label(data, "body.stature_m") == ("body stature", "m")
    assert axis_label(data, "solver") == ("IK solver", "")


@pytest.mark.parametrize(
    ("vary", "shown"),
    [
        ("tasks[2].target_mx[2],tasks[3].target_m[2]=1.2", "target_mx"),
        ("tasks[2].target_m[2],loads[0].mass_kg=1.0", "loads[0].mass_kg in kg"),
        (f"{HEIGHTS}=1.2,25", "25"),
        ("tasks[2].target_m[2],tasks[9].target_m[2]=1.2", "tasks[9]"),
        ("tasks[2].target_m[2],=1.2", "KEY1,KEY2"),
        ("solver,body.sex=nullspace", "solver varied on its own"),
    ],
)
def test_bad_tied_input_is_one_line_and_exit_2(tmp_path: Path, vary: str, shown: str) -> None:
    args = ["whatif", str(SHELF), "--static", "--vary", vary, "--out", str(tmp_path / "w")]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "expected" in lines[0] and shown in lines[0], lines
    assert not (tmp_path / "w").exists()


def test_a_key_tied_and_varied_alone_is_refused(tmp_path: Path) -> None:
    args = ["whatif", str(SHELF), "--static", "--vary", f"{HEIGHTS}=1.2,1.4"]
    args += ["--vary", "tasks[3].target_m[2]=1.0", "--out", str(tmp_path / "w")]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 2
    assert "each key varied once" in result.stderr and len(result.stderr.splitlines()) == 1


def test_the_table_shows_a_tied_axis_once(tmp_path: Path) -> None:
    args = ["whatif", str(SHELF), "--static", "--vary", f"{HEIGHTS}=1.2,1.4"]
    result = CliRunner().invoke(main, [*args, "--out", str(tmp_path / "w"), "--quiet"])
    assert result.exit_code in (0, 1), result.output
    header = next(line for line in result.stdout.splitlines() if line.startswith("tasks"))
    assert header.split()[0] == HEIGHTS and header.count("target_m") == 2
    values = [line.split()[0] for line in result.stdout.splitlines() if line[:1] == " "]
    assert values[:2] == ["1.20", "1.40"]


def test_paired_still_pairs_the_ith_values(tmp_path: Path) -> None:
    """A small woman against a tall man: two cases, each the answer of its own problem."""
    args = ["whatif", str(HOLD), "--static", "--paired", "--vary", "body.sex=female,male"]
    args += ["--vary", "body.stature_m=1.52,1.87", "--out", str(tmp_path / "p"), "--quiet"]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    table = [line.split() for line in result.stdout.splitlines()]
    cases = [line for line in table if line[:1] in (["female"], ["male"])]
    assert [line[:2] for line in cases] == [["female", "1.52"], ["male", "1.87"]]
    for line in cases:
        alone = _endurance_min({"body.sex": line[0], "body.stature_m": float(line[1])})
        assert float(line[5]) == pytest.approx(alone, abs=0.005)
    figures = sorted(p.name for p in (tmp_path / "p").glob("whatif_*.png"))
    assert len(figures) == 4 and all(name.endswith("_vs_body.sex.png") for name in figures)
    short = [a.replace("1.52,1.87", "1.52") for a in args]
    uneven = CliRunner().invoke(main, [*short, "--force"])
    assert uneven.exit_code == 2 and "lists of one length with --paired" in uneven.stderr


def test_case_names_are_short_readable_unique_and_safe_as_folders(tmp_path: Path) -> None:
    """Both hands' heights and both halves of the box: each case is named by each axis's
    last key part and its value (it was ``tasks_2_.target_m_2_,tasks_3_.target_m_2_=1.2__
    loads_0_.mass_kg,loads_1_.mass_kg=2.0``); two axes of one last part keep one part more;
    values a folder cannot hold, or too many characters, end in a digest instead of
    colliding; a grid is resumed under the same names."""
    cases = grid(SHELF, [(HEIGHTS, [1.2, 1.4]), (HALVES, [2.0, 4.0])], solver=None, simulate=False)
    assert [c.name for c in cases] == [
        "target_m_2=1.2,mass_kg=2",
        "target_m_2=1.2,mass_kg=4",
        "target_m_2=1.4,mass_kg=2",
        "target_m_2=1.4,mass_kg=4",
    ]
    split = [("loads[0].mass_kg", [2.5]), ("loads[1].mass_kg", [3]), ("solver", ["nullspace"])]
    (alone,) = grid(SHELF, split, solver=None, simulate=False)
    assert alone.name == "loads_0.mass_kg=2.5,loads_1.mass_kg=3,solver=nullspace"
    titles = ["a/b", "a b", "a?b", "x" * 300]
    names = [c.name for c in grid(HOLD, [("title", titles)], solver=None, simulate=False)]
    assert len(set(names)) == 4 and all(len(n) <= 80 and "/" not in n for n in names)
    assert all(n.startswith("title=a_b-") for n in names[:3])
    assert grid(HOLD, [("title", titles)], solver=None, simulate=False)[3].name == names[3]
    args = ["whatif", str(HOLD), "--vary", "loads[0].mass_kg=1,2.5", "--static", "--quiet"]
    out = ["--out", str(tmp_path / "w")]
    assert CliRunner().invoke(main, [*args, *out]).exit_code == 0
    folders = sorted((tmp_path / "w" / "cases").iterdir())
    assert [p.name for p in folders] == ["mass_kg=1", "mass_kg=2.5"]
    stamps = [(p / "row.json").stat().st_mtime_ns for p in folders]
    assert CliRunner().invoke(main, [*args, *out, "--resume"]).exit_code == 0
    assert [(p / "row.json").stat().st_mtime_ns for p in folders] == stamps  # none run again
    run = tmp_path / "w" / "run.json"  # a grid started under the old names
    record = json.loads(run.read_text())
    record["cases"] = {f"loads_0_.{k}": v for k, v in record["cases"].items()}
    run.write_text(json.dumps(record))
    for folder in folders:
        folder.rename(folder.with_name(f"loads_0_.{folder.name}"))
    old = CliRunner().invoke(main, [*args, *out, "--resume"])
    assert old.exit_code == 2 and "the case names of an earlier version: run it again" in old.output
