"""Figures of 3-D bodies: the posture views, the fatigue by body region, the animation."""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import matplotlib.pyplot as plt
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import PROBLEMS
from PIL import Image

import casadi_posture as cp
from casadi_posture.cli import main
from casadi_posture.output import animation, scene
from casadi_posture.output.animation import frame_steps, write_animation
from casadi_posture.output.figures3d import postures_3d_figure
from casadi_posture.output.plots import REGION_MIN_FATIGUE, fatigue_regions_figure

HUMANOID = Path(__file__).resolve().parents[1] / "benchmarks" / "problems" / "humanoid_28.toml"
ARM = PROBLEMS / "holding_m45.toml"

#: Short runs: 11 steps of 10 s.
SHORT = {"simulation.duration_s": 100.0, "simulation.time_step_s": 10.0}


@pytest.fixture(scope="module")
def humanoid() -> cp.api.Simulation:
    return cp.simulate(cp.load(HUMANOID, SHORT))


@pytest.fixture(scope="module")
def arm() -> cp.api.Simulation:
    return cp.simulate(cp.load(ARM, {"simulation.duration_s": 300.0}))


def test_planar_bodies_keep_the_plane_figure_and_3d_bodies_get_four_views(
    humanoid: cp.api.Simulation, arm: cp.api.Simulation, tmp_path: Path
) -> None:
    assert arm.result.problem.body.planar
    assert not humanoid.result.problem.body.planar
    for name, run in (("humanoid", humanoid), ("arm", arm)):
        files = run.write(tmp_path / name)
        names = {f.name for f in files}
        assert {"postures.png", "fatigue.png", "fatigue_regions.png"} <= names
        for figure in files:
            if figure.suffix == ".png":
                assert figure.stat().st_size > 10_000, figure
                assert Image.open(figure).size[0] > 500


def _by_gid(artists: list, gid: str) -> list:
    return [a for a in artists if a.get_gid() == gid and a.get_visible()]


def test_the_3d_figure_draws_the_support_polygon_and_com_it_is_given(
    humanoid: cp.api.Simulation, monkeypatch: pytest.MonkeyPatch
) -> None:
    square = np.array([[0.1, -0.1], [0.3, -0.1], [0.3, 0.1], [0.1, 0.1]])
    monkeypatch.setattr(scene, "support_polygon", lambda body, q: square)
    result = humanoid.result
    body = result.problem.body
    # The centre of mass the balance counts: the body's and the held loads'.
    loads = [(load.at, load.mass) for load in result.problem.loads]
    mass = body.total_mass + sum(m for _, m in loads)
    weighted = body.com() * body.total_mass + sum(body.landmark(at) * m for at, m in loads)
    com = np.asarray(ca.Function("com", [body.q], [weighted / mass])(result.timeline.q[0])).ravel()
    balance = result.timeline.balance
    assert balance is None or np.allclose(com[:2], balance[0][0])
    fig = postures_3d_figure(result)
    views = {ax.get_label(): ax for ax in fig.axes}
    assert {"sagittal", "frontal", "top", "3-D"} <= set(views)

    top = views["top"]
    (polygon,) = _by_gid(top.patches, "support")  # the same polygon for every posture: once
    np.testing.assert_allclose(polygon.get_xy()[:4], square)
    initial = _by_gid(top.lines, "com")[0]
    np.testing.assert_allclose(initial.get_xydata()[0], com[:2], atol=1e-12)

    sagittal = views["sagittal"]
    drop = _by_gid(sagittal.lines, "com-drop")[0].get_xydata()
    np.testing.assert_allclose(drop, [[com[0], com[2]], [com[0], 0.0]], atol=1e-12)
    (floor,) = _by_gid(sagittal.lines, "support")
    np.testing.assert_allclose(floor.get_xydata(), [[0.1, 0.0], [0.3, 0.0]])

    marker = _by_gid(views["3-D"].lines, "com")[0]
    np.testing.assert_allclose(np.ravel(marker.get_data_3d()), com, atol=1e-12)
    for name in ("sagittal", "frontal", "top"):
        assert views[name].get_aspect() == 1.0
    plt.close(fig)


def test_the_region_figure_has_one_panel_per_tired_region(arm: cp.api.Simulation) -> None:
    result = arm.result
    halves = result.problem.body.half_joints
    peak = result.timeline.fatigue.max(axis=0)
    tired = {h.region for h, p in zip(halves, peak, strict=True) if p > REGION_MIN_FATIGUE}
    fig = fatigue_regions_figure(result)
    panels = [ax for ax in fig.axes if ax.get_label() in tired]
    assert len(panels) == len(fig.axes) == len(tired) == 2
    assert panels[0].get_label() == "shoulder"  # the shoulder flexors tire first
    for ax in panels:
        assert ax.get_xlabel() in ("", "time (min)")
        curves = [line for line in ax.lines if np.ptp(line.get_ydata()) > 0]
        assert curves and max(np.max(c.get_ydata()) for c in curves) > REGION_MIN_FATIGUE
    plt.close(fig)


def test_frames_are_spread_over_a_long_run() -> None:
    steps = frame_steps(1201)
    assert len(steps) == animation.MAX_FRAMES and steps[0] == 0 and steps[-1] == 1200
    assert frame_steps(11) == list(range(11))


@pytest.mark.parametrize("which", ["humanoid", "arm"])
def test_the_animation_has_a_frame_per_step_and_leaves_no_temporary_file(
    which: str, request: pytest.FixtureRequest, tmp_path: Path
) -> None:
    run = request.getfixturevalue(which)
    if which == "arm":
        run = cp.simulate(cp.load(ARM, SHORT))
    path = run.animate(tmp_path / "hold.gif")
    assert path == tmp_path / "hold.gif"
    with Image.open(path) as gif:
        assert gif.n_frames == run.result.timeline.time.size == 11
    assert [p.name for p in tmp_path.iterdir()] == ["hold.gif"]
    with pytest.raises(cp.ProblemError, match="new or empty"):
        run.animate(path)
    with pytest.raises(cp.ProblemError, match="one of gif, mp4"):
        run.animate(tmp_path / "hold.avi")


def test_ctrl_c_while_writing_leaves_no_file(
    humanoid: cp.api.Simulation, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    grabbed = []
    original = animation.animation.PillowWriter.grab_frame

    def grab(self: animation.animation.PillowWriter, **kwargs: object) -> None:
        original(self, **kwargs)
        grabbed.append(1)
        if len(grabbed) == 3:
            raise KeyboardInterrupt  # a second Ctrl-C, or one outside a command

    monkeypatch.setattr(animation.animation.PillowWriter, "grab_frame", grab)
    with pytest.raises(KeyboardInterrupt):
        write_animation(humanoid.result, tmp_path / "hold.gif")
    assert list(tmp_path.iterdir()) == []

    monkeypatch.setattr(animation.interrupt, "requested", lambda: len(grabbed) >= 5)
    assert write_animation(humanoid.result, tmp_path / "hold.gif") is None  # Ctrl-C in simulate
    assert list(tmp_path.iterdir()) == []
    assert write_animation(humanoid.result, tmp_path / "hold.gif") is None  # pressed before
    assert list(tmp_path.iterdir()) == []


def test_simulate_animate_writes_a_gif_and_mp4_needs_ffmpeg(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    args = ["simulate", str(ARM), "--duration", "20", "--out", str(tmp_path / "run")]
    result = CliRunner().invoke(main, [*args, "--animate"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "run" / "animation.gif").stat().st_size > 0
    assert not list((tmp_path / "run").glob(".*"))

    monkeypatch.setattr(animation.animation.writers, "is_available", lambda name: False)
    args[-1] = str(tmp_path / "mp4")
    result = CliRunner().invoke(main, [*args, "--animate", "mp4"])
    assert result.exit_code == 2
    assert result.stderr.strip().splitlines() == [
        "error: --animate = 'mp4': expected gif (mp4 needs an ffmpeg program on the PATH, "
        "and none was found)"
    ]
    assert not (tmp_path / "mp4").exists()
