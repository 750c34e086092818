"""Figures of 3-D bodies: the posture views, the fatigue by body region, the animation."""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import matplotlib.pyplot as plt
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import PROBLEMS
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_rgba
from matplotlib.path import Path as Outline
from PIL import Image

import casadi_posture as cp
from casadi_posture.cli import main
from casadi_posture.output import animation, figures3d, mannequin, scene
from casadi_posture.output.animation import frame_steps, write_animation
from casadi_posture.output.figures3d import postures_3d_figure
from casadi_posture.output.key_postures import key_postures
from casadi_posture.output.plots import REGION_MIN_FATIGUE, fatigue_regions_figure
from casadi_posture.output.skeleton import Skeleton
from casadi_posture.output.time_axis import time_unit

HUMANOID = Path(__file__).resolve().parents[1] / "benchmarks" / "problems" / "humanoid_28.toml"
ARM = PROBLEMS / "holding_m45.toml"

#: Short runs: 11 steps of 10 s; the wall's until its shoulder flexors have reached the
#: fatigue threshold (at 244 s) and the constraint has moved it.
SHORT = {"simulation.duration_s": 100.0, "simulation.time_step_s": 10.0}
WALL_SHORT = {"simulation.duration_s": 300.0, "simulation.time_step_s": 10.0}


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
        assert ax.get_xlabel() in ("", "time (s)")  # a run of 5 minutes: in seconds
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


# The mannequin: the 3-D human bodies drawn as a person.

WALL = PROBLEMS / "standing_wall_horizontal.toml"
SEATED = PROBLEMS / "seated_assembly.toml"


@pytest.fixture(scope="module")
def wall() -> cp.api.Simulation:
    return cp.simulate(cp.load(WALL, WALL_SHORT))


def _inside(point: np.ndarray, points: np.ndarray) -> bool:
    """Whether ``point`` lies in the convex hull of ``points`` seen along every world axis
    (a necessary condition of lying in the 3-D hull)."""
    for axes in ([0, 2], [1, 2], [0, 1]):
        outline = Outline(mannequin.hull(points[:, axes]))
        if not outline.contains_point(point[axes], radius=1e-9):
            return False
    return True


def test_every_joint_centre_of_the_standing_body_lies_inside_its_mannequin() -> None:
    body = cp.load(WALL).body
    rng = np.random.default_rng(7)
    q = rng.uniform(np.maximum(body.lower, -0.8), np.minimum(body.upper, 0.8), (2, body.n))
    skeleton = Skeleton(body, q)
    names = {p.name for p in skeleton.parts}
    limbs = [f"{k}_{s}" for k in ("upper_arm", "forearm", "hand", "thigh", "shank", "foot")
             for s in "rl"]  # fmt: skip
    assert {"head", "neck", "torso", "pelvis", *limbs} <= names
    # The joint centres, by the body's own kinematics (not the mannequin's frames); the
    # vertex, heels and toes lie on the skin, not inside.
    joints = [n for n in body.landmarks if not n.startswith(("vertex", "heel", "toe"))]
    position = ca.Function("lm", [body.q], [ca.horzcat(*[body.landmark(n) for n in joints])])
    for step in range(len(q)):
        solids = [points.reshape(-1, 3) for points in skeleton.solids(step)]
        xyz = np.asarray(position(q[step])).T
        for name, point in zip(joints, xyz, strict=True):
            assert any(_inside(point, s) for s in solids), (name, step)
        # Each limb segment's solid holds both its end joints.
        for part, points in zip(skeleton.parts, solids, strict=True):
            segment = next((s for s in body.segments if s.name == part.name), None)
            if segment is not None and part.limb and not part.name.startswith("foot"):
                for end in (segment.proximal, segment.distal):
                    assert _inside(xyz[joints.index(end)], points), (part.name, end)


def test_the_mannequin_is_as_tall_as_the_body_and_stands_on_the_floor() -> None:
    problem = cp.load(WALL)
    skeleton = Skeleton(problem.body, np.zeros((1, problem.body.n)))
    points = np.vstack([p.reshape(-1, 3) for p in skeleton.solids(0)])
    assert points[:, 2].max() == pytest.approx(problem.spec.body.stature_m, abs=0.015)
    assert points[:, 2].min() == pytest.approx(0.0, abs=1e-3)
    # Shoulder breadth over the deltoids: about a quarter of the stature or more
    # (ANSUR II men: some 0.49-0.51 m at 1.756 m); the body is narrower at the hips.
    shoulders = points[np.abs(points[:, 2] - 1.36) < 0.05, 1]
    assert 0.45 < np.ptp(shoulders) < 0.56


def test_a_seated_upper_body_sits_on_a_stool_with_its_feet_on_the_floor() -> None:
    problem = cp.load(SEATED)
    skeleton = Skeleton(problem.body, np.zeros((1, problem.body.n)))
    parts = {p.name: points for p, points in zip(skeleton.parts, skeleton.solids(0), strict=True)}
    context = {p.name for p in skeleton.parts if p.context}
    assert context == {"seat", "post", "base"} | {
        f"{k}_{s}" for k in ("thigh", "shank", "foot") for s in "rl"
    }
    # The problem file's 0.46 m seat under hips at 0.55 m; feet flat on the floor.
    assert parts["seat"][..., 2].max() == pytest.approx(0.46, abs=0.005)
    for side in "rl":
        assert parts[f"foot_{side}"][..., 2].min() == pytest.approx(0.0, abs=1e-3)
    # Drawn only: the legs and stool are in no task limb and weigh nothing.
    assert mannequin.limbs_of(problem.body, skeleton.parts, ["hip_r", "c7"]) == set()


def _fills(ax: object, name: str) -> list[np.ndarray]:
    return [np.asarray(p.get_facecolor()) for p in ax.patches if p.get_gid() == f"body:{name}"]


def test_the_figure_draws_a_person_its_task_limb_deeper_and_a_large_3d_view(
    wall: cp.api.Simulation,
) -> None:
    result = wall.result
    fig = postures_3d_figure(result)
    views = {ax.get_label(): ax for ax in fig.axes}
    postures = len(key_postures(result))
    assert postures >= 2
    body = result.problem.body
    eyes = np.asarray(ca.Function("e", [body.q], [body.landmark("eyes")])(result.timeline.q[0]))
    for name in ("sagittal", "frontal", "top"):
        ax = views[name]
        assert not _by_gid(ax.lines, "bones")[0].get_xydata().size  # no stick figure
        heads = [p for p in ax.patches if p.get_gid() == "body:head"]
        assert len(heads) == postures
        axes = list(scene.VIEWS[name][0])
        assert heads[0].get_path().contains_point(eyes.ravel()[axes])
        # The limb carrying the load and the tasks' effector (wrist_r) is deeper in every
        # posture; the idle arm as light as the trunk.
        for task, idle, trunk in zip(
            _fills(ax, "forearm_r"), _fills(ax, "forearm_l"), _fills(ax, "torso"), strict=True
        ):
            assert idle[:3].mean() - task[:3].mean() > 0.2
            np.testing.assert_allclose(idle, trunk)
        # The initial posture opaque, the others translucent within opaque outlines.
        alphas = [f[3] for f in _fills(ax, "torso")]
        assert alphas[0] == 1.0 and max(alphas[1:]) < 0.5
        edges = [p.get_edgecolor()[3] for p in ax.patches if p.get_gid() == "body:torso"]
        assert min(edges) == 1.0
    surfaces = [c for c in views["3-D"].collections if c.get_gid() == "mannequin"]
    assert len(surfaces) == postures
    # The 3-D view at least three quarters the size of the sagittal view's height.
    inches = fig.get_size_inches()
    side = views["3-D"].get_position().width * inches[0]
    assert side >= 0.75 * views["sagittal"].get_position().height * inches[1]
    assert inches[0] <= figures3d.WIDTH_IN + 1.2
    plt.close(fig)


def test_a_body_that_is_not_human_stays_a_stick_figure(humanoid: cp.api.Simulation) -> None:
    fig = postures_3d_figure(humanoid.result)
    sagittal = next(ax for ax in fig.axes if ax.get_label() == "sagittal")
    assert not [p for p in sagittal.patches if str(p.get_gid()).startswith("body:")]
    assert _by_gid(sagittal.lines, "bones")[0].get_xydata().size
    plt.close(fig)


def test_the_animation_recolours_the_mannequin(wall: cp.api.Simulation) -> None:
    result = wall.result
    frames = animation._Frames(result, list(range(result.timeline.time.size)))
    on = int(np.argmax(result.timeline.owner >= 0))
    assert result.timeline.owner[on] >= 0 and result.timeline.owner[0] < 0
    side = next(ax for ax in frames.fig.axes if ax.get_label() != "3-D" and ax.patches)
    for step, colour in ((0, animation.FREE), (on, animation.CONSTRAINED)):
        frames.draw(step)
        torso = next(p for p in side.patches if p.get_gid() == "body:torso")
        np.testing.assert_allclose(torso.get_edgecolor(), to_rgba(colour))
        assert torso.get_facecolor()[3] == 1.0
    plt.close(frames.fig)


def test_figures_give_time_in_minutes_only_past_five_minutes() -> None:
    """A recorded cycle of seconds reads in seconds; the report's rule (over 300 s: min)."""
    assert time_unit(np.array([0.0, 5.78])) == (1.0, "s")
    assert time_unit(np.array([0.0, 300.0])) == (1.0, "s")
    assert time_unit(np.array([10.0, 311.0])) == (60.0, "min")


def test_a_frame_drawn_over_the_first_is_the_whole_figure_drawn_again(
    wall: cp.api.Simulation,
) -> None:
    """The animation's frames paint only what moves over the first draw: each is, pixel
    for pixel, the figure drawn whole, but where the time cursor crosses the fatigue
    strip's frame (the whole draw puts the frame over it)."""
    result = wall.result
    on = int(np.argmax(result.timeline.owner >= 0))
    frames = animation._Frames(result, [0, on, result.timeline.time.size - 1])
    canvas = FigureCanvasAgg(frames.fig)
    for step in (0, on, result.timeline.time.size - 1):
        frames.draw(step)
        canvas.draw()
        moved = np.asarray(canvas.buffer_rgba()).copy()
        for artist in frames.fig.moving:
            artist.set_animated(False)
        animation.Figure.draw(frames.fig, canvas.get_renderer())
        whole = np.asarray(canvas.buffer_rgba())
        apart = np.flatnonzero(np.abs(moved.astype(int) - whole).sum(axis=2).any(axis=0))
        cursor = frames.cursor.get_transform().transform((frames.cursor.get_xdata()[0], 0))[0]
        assert np.all(np.abs(apart - cursor) <= 2), (step, apart)
        for artist in frames.fig.moving:
            artist.set_animated(True)
    plt.close(frames.fig)
