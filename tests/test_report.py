"""report.html: written beside a run's files (not with --no-report), within its size bound,
and working in a real browser (Debian's headless Chromium driven by Playwright): no
console error, the slider moves the body to the postures the run computed, the page is
drawn."""

from __future__ import annotations

import json
import re
import time
from pathlib import Path
from urllib.parse import unquote

import numpy as np
import pytest
from click.testing import CliRunner

from casadi_posture import api, interrupt
from casadi_posture.cli import main
from casadi_posture.output.html_body import placements
from casadi_posture.output.html_report import frame_steps, shown_groups, write_report
from casadi_posture.output.plotly_json import rounded
from casadi_posture.output.scene import Scene
from casadi_posture.output.skeleton import Skeleton
from tests.browser import mesh_of, open_page, pixels_of

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"

#: The standing wall hold for 300 s: the right shoulder flexors reach the fatigue
#: threshold at 244 s and the constraint takes over (two events), so the posture moves.
STANDING = {"simulation.duration_s": 300.0}


@pytest.fixture(scope="module")
def standing(tmp_path_factory: pytest.TempPathFactory):
    out = tmp_path_factory.mktemp("standing")
    run = api.simulate(api.load(PROBLEMS / "standing_wall_horizontal.toml", STANDING))
    files = run.write(out, figures=False)
    return run, out, files


def test_the_report_is_written_beside_the_run_s_files(standing) -> None:
    _, out, files = standing
    assert out / "report.html" in files and (out / "report.html").stat().st_size > 1e6
    assert not list(out.glob("*.partial"))


def test_the_slider_shows_every_event_and_at_most_the_limit_besides() -> None:
    time_s = np.arange(0.0, 1201.0)
    events = [80.0, 80.0, 365.5, 1199.0]
    steps = frame_steps(time_s, events, limit=50)
    assert steps[0] == 0 and steps[-1] == 1200 and np.all(np.diff(steps) > 0)
    assert {80, 366, 1199} <= set(steps.tolist()) and len(steps) <= 50 + 3
    assert len(frame_steps(time_s[:20], [], limit=300)) == 20


def test_numbers_keep_four_significant_digits() -> None:
    assert rounded([1234.5678, 0.000123456, -2.0, float("nan")]) == [1235.0, 0.0001235, -2.0, None]
    assert rounded([[0.0, float("inf")], [-0.0, 99999.0]]) == [[0.0, None], [-0.0, 1e5]]


def test_rounding_in_arrays_gives_the_decimal_formatting_s_numbers() -> None:
    """The page's numbers are rounded for all of them at once; each is the double Python's
    own formatting to 4 (or 6) significant digits gives, so it prints as short."""
    rng = np.random.default_rng(7)
    values = rng.uniform(-1, 1, 20000) * 10.0 ** rng.integers(-12, 13, 20000)
    for digits in (4, 6):
        expected = [float(f"{v:.{digits}g}") for v in values]
        got = rounded(values, digits)
        differ = [(e, g) for e, g in zip(expected, got, strict=True) if e != g]
        # only a tie can round the other way (a value a few ulps from ...5 at the last digit)
        assert len(differ) <= 2, differ[:5]
        assert all(abs(e - g) <= 10 ** (np.floor(np.log10(abs(e))) - digits + 2) for e, g in differ)
        mantissas = [repr(abs(g)).split("e")[0].replace(".", "").strip("0") for g in got]
        assert max(len(m) for m in mantissas) <= digits  # printed short: no 0.12340000000001


def test_the_curves_show_the_groups_that_tire_most(standing) -> None:
    run, _, _ = standing
    tl, halves = run.result.timeline, [h.name for h in run.result.problem.body.half_joints]
    shown = shown_groups(run.result)
    assert len(shown) == 8 and halves[shown[0]] == "shoulder_flexors_r"
    peaks = tl.fatigue.max(axis=0)
    assert peaks[shown].min() >= np.sort(peaks)[-8]  # no group left out tires more


def test_the_mannequin_s_extent_is_that_of_every_point_placed(standing) -> None:
    """The box and the mean of the mannequin's points over many postures, summed without
    placing each point, against every point placed."""
    run, _, _ = standing
    skeleton = Skeleton(run.result.problem.body, run.result.timeline.q)
    steps = [0, 120, 250, 299]
    every = np.vstack([p.reshape(-1, 3) for s in steps for p in skeleton.solids(s)])
    lo, hi, total, count = skeleton.solids_extent(steps)
    assert count == len(every)
    np.testing.assert_allclose(lo, every.min(axis=0), atol=1e-12)
    np.testing.assert_allclose(hi, every.max(axis=0), atol=1e-12)
    np.testing.assert_allclose(total / count, every.mean(axis=0), atol=1e-12)


def test_a_skeleton_placed_at_a_few_steps_is_the_whole_one_there(standing) -> None:
    """A figure's few postures placed alone (``steps``) are those of the whole run's
    skeleton; the rows not placed are NaN, never a wrong posture."""
    run, _, _ = standing
    body, q = run.result.problem.body, run.result.timeline.q
    whole, steps = Skeleton(body, q), [250, 0, 250, 299]
    few = Skeleton(body, q, steps=steps)
    for step in steps:
        np.testing.assert_allclose(few.points[step], whole.points[step], atol=1e-12)
        np.testing.assert_allclose(few.com[step], whole.com[step], atol=1e-12)
        for a, b in zip(few.solids(step), whole.solids(step), strict=True):
            np.testing.assert_allclose(a, b, atol=1e-12)
    assert np.isnan(few.points[120]).all() and np.isnan(few.com[120]).all()


def test_the_placements_move_the_mannequin_where_the_skeleton_puts_it(standing) -> None:
    """The page moves each part by its frame's placement (t + R·x0); at a step after the
    posture changed this gives the skeleton's own solids (output/skeleton.py)."""
    run, _, _ = standing
    result = run.result
    skeleton = Skeleton(result.problem.body, result.timeline.q)
    frames = list(dict.fromkeys(part.dof for part in skeleton.parts))
    step = result.timeline.time.size - 1
    placed = placements(result.problem.body, result.timeline.q, frames, np.array([0, step]))[1]
    for part, solid in zip(skeleton.parts, skeleton.solids(step), strict=True):
        t, rotation = placed[frames.index(part.dof), :, 0], placed[frames.index(part.dof), :, 1:]
        np.testing.assert_allclose(t + part.points() @ rotation.T, solid, atol=1e-12)


def test_the_report_works_in_a_browser(standing, browser, tmp_path: Path) -> None:
    run, out, _ = standing
    result = run.result
    page, errors = open_page(browser, out / "report.html")
    data = json.loads(page.inner_text("#report-data"))
    last = len(data["time"]) - 1
    first = mesh_of(page)
    before = page.locator("#body").screenshot()
    page.locator("#slider").fill(str(last))  # as a user drags it: an input event
    page.wait_for_function(f"window.reportFrame === {last}")
    moved = mesh_of(page)
    assert not errors, errors
    # The body drawn at the last moment is the run's last posture (to the page's rounding).
    step = int(np.searchsorted(result.timeline.time, data["time"][last]))
    assert step == result.timeline.time.size - 1
    scene = Scene.of_run(result, [step])
    solids = scene.skeleton.solids(step)
    for name, task in (("body", False), ("task limbs", True)):
        expected = [
            solid.reshape(-1, 3)
            for part, solid in zip(scene.skeleton.parts, solids, strict=True)
            if not part.context and (part.limb in scene.task_limbs) == task
        ]
        np.testing.assert_allclose(moved[name], np.vstack(expected), atol=2e-3)
    assert np.abs(moved["task limbs"] - first["task limbs"]).max() > 0.05  # the arm moved
    # The cursor on the curves follows: at the last moment's time.
    cursor = page.evaluate("document.getElementById('curves').layout.shapes.at(-1).x0")
    assert cursor == pytest.approx(data["time"][last] / data["scale"])
    assert page.inner_text("#clock").startswith(f"t = {data['time'][last]:g} s")
    after = page.locator("#body").screenshot()
    pixels = [pixels_of(shot) for shot in (before, after)]
    for image in pixels:
        assert image.std() > 20  # not blank
        blue = image[..., 2].astype(int) - image[..., 0] > 40  # the body, not the grey box
        assert blue.mean() > 0.01
    assert np.abs(pixels[0].astype(int) - pixels[1]).max() > 100  # the body moved on screen
    page.screenshot(path=str(tmp_path / "report.png"), full_page=True)
    page.close()


def test_a_planar_arm_is_drawn_in_its_plane(browser, tmp_path: Path) -> None:
    run = api.simulate(api.load(PROBLEMS / "holding_m45.toml", {"simulation.duration_s": 60.0}))
    path = write_report(run.result, tmp_path / "report.html")
    page, errors = open_page(browser, path)
    kinds = page.evaluate("document.getElementById('body').data.map(t => t.type)")
    assert set(kinds) == {"scatter"} and not errors, (kinds, errors)
    body = page.evaluate("document.getElementById('body').data.find(t => t.name === 'body')")
    tl = run.result.timeline
    skeleton = Skeleton(run.result.problem.body, tl.q)
    i, j = skeleton.plane
    bones = skeleton.segments(0)
    drawn = np.array([[np.nan if v is None else v for v in body[a]] for a in "xy"]).T
    np.testing.assert_allclose(drawn, bones[:, [i, j]], atol=1e-3)
    page.close()


def test_no_report_writes_none(tmp_path: Path) -> None:
    out = tmp_path / "run"
    args = ["simulate", str(PROBLEMS / "holding_m45.toml"), "--duration", "20", "--no-report"]
    result = CliRunner().invoke(main, [*args, "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert (out / "summary.json").exists() and not (out / "report.html").exists()
    assert "report.html" not in result.output


def test_an_interrupted_run_gets_a_report_of_its_steps(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls = iter(range(10**6))
    monkeypatch.setattr(interrupt, "requested", lambda: next(calls) >= 15)
    out = tmp_path / "run"
    args = ["simulate", str(PROBLEMS / "holding_m45.toml"), "--out", str(out)]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 130, result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stop"] == "interrupted"
    page = (out / "report.html").read_text()
    assert "FLAGGED: interrupted at" in page
    data = json.loads(re.search(r'id="report-data"[^>]*>(.*?)</script>', page, re.S).group(1))
    assert data["time"][-1] == summary["simulated_s"] < 20


@pytest.mark.slow
def test_a_20_minute_standing_report_is_under_5_mb(tmp_path: Path) -> None:
    """The 29-DOF body at the wall with 1.6 kg for 20 min: 1201 steps, two cycles."""
    sets = {"simulation.duration_s": 1200.0, "loads[0].mass_kg": 1.6}
    run = api.simulate(api.load(PROBLEMS / "standing_wall_horizontal.toml", sets))
    assert run.result.timeline.time.size == 1201 and run.summary()["fatigue_recovery_cycles"] >= 2
    start = time.perf_counter()
    path = write_report(run.result, tmp_path / "report.html")
    took = time.perf_counter() - start
    assert path.stat().st_size < 5e6 and took < 30, (path.stat().st_size, took)


@pytest.fixture(scope="module")
def grid(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A what-if of three loads on the arm, 60 s each: its page and each case's report."""
    out = tmp_path_factory.mktemp("grid") / "w"
    api.whatif(
        PROBLEMS / "holding_m45.toml",
        {"loads[0].mass_kg": [1.0, 2.5, 4.0]},
        out,
        overrides={"simulation.duration_s": 60.0},
    )
    return out


def test_a_what_if_page_links_every_case_to_its_own_report(grid: Path) -> None:
    """One row per case with the varied value, linked to the case's report.html (which
    exists), the columns the cases share listed once above the table, the figures
    embedded."""
    text = (grid / "report.html").read_text()
    links = re.findall(r'<a href="([^"]+)">', text)
    assert len(links) == len(list((grid / "cases").iterdir())) == 3
    assert all((grid / unquote(link)).exists() for link in links)
    assert "The same for every case" in text and "<th>loads[0].mass_kg</th>" in text
    assert text.count("data:image/png;base64,") == len(list(grid.glob("whatif_*.png"))) > 0


def test_the_what_if_page_sorts_by_a_column_in_the_browser(grid: Path, browser) -> None:
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto((grid / "report.html").resolve().as_uri())
    column = "loads[0].mass_kg"
    values = lambda: page.evaluate(  # noqa: E731
        "(c) => { const i = [...document.querySelectorAll('#grid th')].findIndex("
        "h => h.textContent.replace(/ [▲▼]$/, '') === c);"
        " return [...document.querySelectorAll('#grid tbody tr')]"
        ".map(r => r.cells[i].textContent) }",
        column,
    )
    header = page.locator("#grid th", has_text=column)
    header.click()
    assert [float(v) for v in values()] == [1.0, 2.5, 4.0]
    header.click()
    assert [float(v) for v in values()] == [4.0, 2.5, 1.0]
    assert not errors
    page.close()


def _batch(out: Path, *extra: str):
    """casadi-posture batch on the arm for 30 s into ``out``, with ``extra`` options."""
    arm = str(PROBLEMS / "holding_m45.toml")
    args = ["batch", arm, "--out", str(out), "--set", "simulation.duration_s=30", "--quiet"]
    return CliRunner().invoke(main, [*args, *extra])


def test_no_report_writes_no_page_for_a_grid_nor_its_cases(tmp_path: Path) -> None:
    out = tmp_path / "b"
    result = _batch(out, "--no-report")
    assert result.exit_code == 0, result.output
    assert not list(out.rglob("report.html"))
    again = _batch(out, "--force")
    assert again.exit_code == 0, again.output
    assert (out / "report.html").exists()
    assert (out / "cases" / "holding_m45" / "report.html").exists()


def test_plotly_js_is_compressed_once_into_the_user_s_cache(tmp_path, monkeypatch) -> None:
    """The page's plotly.js inflates to the installed package's; it is kept in the cache
    folder and read back from it; an unwritable cache still gives the page its copy."""
    import base64
    import gzip

    from casadi_posture.output import html_page
    from casadi_posture.output.plotly_json import plotly_js

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    made = html_page.plotly_gzip.__wrapped__()
    assert gzip.decompress(base64.b64decode(made)).decode() == plotly_js()
    (kept,) = (tmp_path / "cache" / "casadi_posture").iterdir()
    assert kept.read_text() == made and html_page.plotly_gzip.__wrapped__() == made
    (tmp_path / "file").write_text("")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "file"))  # a file: no folder in it
    assert html_page.plotly_gzip.__wrapped__() == made
