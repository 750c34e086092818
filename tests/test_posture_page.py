"""report.html of solve and compare: written with --out (not with --no-report), the files
agree with the console, and in a real browser each posture button puts the drawn body on
that posture and each row of compare's table shows its problem."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from casadi_posture import api
from casadi_posture.cli import main
from casadi_posture.output.scene import Scene
from tests.browser import mesh_of, open_page, pixels_of
from tests.conftest import PROBLEMS

SHELF = PROBLEMS / "standing_shelf_box.toml"
COMPARED = [PROBLEMS / "holding_m45.toml", PROBLEMS / "standing_wall_m25.toml"]


def _expected(problem, q: np.ndarray) -> dict[str, np.ndarray]:
    """The mannequin's surfaces [m] at posture ``q`` [rad], as the page groups them."""
    scene = Scene(problem, problem.task_objects(), q[None], [0])
    solids = scene.skeleton.solids(0)
    return {
        name: np.vstack(
            [
                solid.reshape(-1, 3)
                for part, solid in zip(scene.skeleton.parts, solids, strict=True)
                if not part.context and (part.limb in scene.task_limbs) == task
            ]
        )
        for name, task in (("body", False), ("task limbs", True))
    }


@pytest.fixture(scope="module")
def solved(tmp_path_factory: pytest.TempPathFactory):
    out = tmp_path_factory.mktemp("solve") / "shelf"
    result = CliRunner().invoke(main, ["solve", str(SHELF), "--out", str(out)])
    assert result.exit_code == 0, result.output
    return out, result.output


def test_solve_writes_what_json_prints_and_a_page(solved) -> None:
    out, output = solved
    assert f"written: {out / 'report.html'}" in output
    printed = json.loads(CliRunner().invoke(main, ["solve", str(SHELF), "--json"]).output)
    written = json.loads((out / "solve.json").read_text())
    for key in ("posture_deg", "levels", "flags", "status", "low_back", "rula_reba"):
        assert written[key] == printed[key], key
    assert written["levels"][-1]["criterion"] and not written["levels"][0]["criterion"]
    assert not list(out.glob("*.partial"))


def test_the_comfort_level_is_minimised_not_failed(solved) -> None:
    _, output = solved
    comfort = next(line for line in output.splitlines() if line.split()[1:2] == ["comfort"])
    assert comfort.split()[-2:] == ["minimised", "(criterion)"]


def test_solve_no_report_and_an_existing_folder(tmp_path: Path) -> None:
    out = tmp_path / "x"
    runner = CliRunner()
    result = runner.invoke(main, ["solve", str(SHELF), "--out", str(out), "--no-report"])
    assert result.exit_code == 0 and sorted(p.name for p in out.iterdir()) == ["solve.json"]
    again = runner.invoke(main, ["solve", str(SHELF), "--out", str(out)])
    assert again.exit_code == 2 and "--force" in again.output and "Traceback" not in again.output
    forced = runner.invoke(main, ["solve", str(SHELF), "--out", str(out), "--force"])
    assert forced.exit_code == 0 and (out / "report.html").exists()


def test_the_solve_page_shows_the_start_and_the_answer(solved, browser, tmp_path: Path) -> None:
    out, _ = solved
    problem = api.load(SHELF)
    answer = np.radians(list(json.loads((out / "solve.json").read_text())["posture_deg"].values()))
    page, errors = open_page(browser, out / "report.html")
    labels = page.locator("#postures button").all_inner_texts()
    assert labels == ["start (posture_deg)", "answer (nullspace)"]
    shots = []
    for k, q in ((1, answer), (0, problem.posture)):  # the answer is shown first
        page.locator("#postures button").nth(k).click()
        page.wait_for_function(f"window.reportPosture === {k}")
        drawn, expected = mesh_of(page), _expected(problem, np.asarray(q))
        for name in expected:
            np.testing.assert_allclose(drawn[name], expected[name], atol=2e-3)
        shots.append(pixels_of(page.locator("#body").screenshot()))
    assert not errors, errors
    assert all(shot.std() > 20 for shot in shots)  # not blank
    assert np.abs(shots[0].astype(int) - shots[1]).max() > 100  # the arms moved on screen
    assert page.locator("text=most tiring: shoulder_flexors").count() == 1
    page.screenshot(path=str(tmp_path / "solve.png"), full_page=True)
    page.close()


@pytest.fixture(scope="module")
def compared(tmp_path_factory: pytest.TempPathFactory):
    out = tmp_path_factory.mktemp("compare") / "both"
    result = CliRunner().invoke(main, ["compare", *map(str, COMPARED), "--out", str(out)])
    assert result.exit_code == 0, result.output
    return out


def test_compare_writes_its_table_and_a_page(compared) -> None:
    with (compared / "compare.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [r["problem"] for r in rows].count(str(COMPARED[1])) == 4
    comfort = [r for r in rows if r["tasks"] == "comfort"]
    assert [r["criterion"] for r in comfort] == ["True"]
    assert all("unreachable" not in r["verdict"] for r in rows)  # comfort is minimised
    assert (compared / "report.html").exists()


def test_a_row_of_the_compare_page_shows_its_problem(compared, browser) -> None:
    page, errors = open_page(browser, compared / "report.html")
    assert page.locator("#index tbody tr").count() == 2
    page.locator("#index tbody tr").nth(1).click()
    page.wait_for_function("window.reportCase === 1")
    problem = api.load(COMPARED[1])
    lexicographic = api.compare(problem).lexicographic.q
    assert page.locator("#postures button").all_inner_texts()[-1] == "lexicographic"
    drawn, expected = mesh_of(page), _expected(problem, lexicographic)
    for name in expected:
        np.testing.assert_allclose(drawn[name], expected[name], atol=2e-3)
    shown = page.locator(".case:visible h2").all_inner_texts()
    assert shown == [str(COMPARED[1])]
    assert not errors, errors
    page.close()


def test_compare_no_report_writes_the_table_only(tmp_path: Path) -> None:
    out = tmp_path / "c"
    result = CliRunner().invoke(
        main, ["compare", str(COMPARED[0]), "--out", str(out), "--no-report"]
    )
    assert result.exit_code == 0 and [p.name for p in out.iterdir()] == ["compare.csv"]
