"""The 3-D human bodies (casadi_posture.body.human) drawn as a mannequin: head, neck,
torso, pelvis and limbs as solids of elliptic cross-sections (rings), each carried by the
frame of its segment, drawn as filled outlines in the orthographic views and as shaded
surfaces in the 3-D view.

The sizes are for drawing only (no mass, inertia or joint centre comes from them): rough
breadths, depths and girths of a man of ANSUR II's mean stature (1.756 m), scaled by the
body's shoulder breadth over ANSUR II's male mean biacromial breadth (0.4157 m)."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import to_rgb, to_rgba
from matplotlib.patches import Patch, Polygon
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from casadi_posture.body.tree import BodyModel

if TYPE_CHECKING:
    from casadi_posture.output.skeleton import Skeleton

#: ANSUR II male mean biacromial breadth [m]: the sizes below are for this shoulder breadth.
REFERENCE_BIACROMIAL = 0.4157

#: Points on each ring, and the angles [rad] of a rounded end's rings (0: the end ring).
RING_POINTS = 16
_CAP = np.radians([22.0, 43.0, 61.0, 76.0, 88.0])

#: The limb segments (side suffix _r, _l) and the limb each belongs to.
LIMBS = {
    "upper_arm": "arm",
    "forearm": "arm",
    "hand": "arm",
    "thigh": "leg",
    "shank": "leg",
    "foot": "leg",
}
SIDES = {"r": "right", "l": "left"}

#: Each limb segment: fractions along it (proximal 0 to distal 1), half-widths and half-
#: depths [m] of the rings there (width across the body, depth front to back at the zero
#: posture), and the lengths [m] of the rounded ends beyond the first and last rings.
_SEGMENTS = {
    "upper_arm": ((0.0, 0.3, 1.0), (0.05, 0.047, 0.038), (0.05, 0.05, 0.04), (0.05, 0.035)),
    "forearm": ((0.0, 0.25, 1.0), (0.04, 0.043, 0.029), (0.04, 0.04, 0.019), (0.03, 0.015)),
    "hand": ((0.0, 1.0, 1.7), (0.03, 0.043, 0.035), (0.017, 0.015, 0.012), (0.01, 0.03)),
    "thigh": ((0.0, 0.25, 1.0), (0.08, 0.083, 0.055), (0.085, 0.088, 0.058), (0.06, 0.04)),
    "shank": ((0.0, 0.3, 1.0), (0.052, 0.056, 0.032), (0.056, 0.062, 0.034), (0.04, 0.03)),
}

#: The foot from heel to toe: fractions along the sole, heights of the rings' centres
#: above it [m], half-widths and half-heights [m], rounded ends [m].
_FOOT = (
    (0.1, 0.3, 0.74, 0.95),
    (0.035, 0.045, 0.022, 0.012),
    (0.033, 0.042, 0.05, 0.03),
    (0.035, 0.045, 0.022, 0.012),
    (0.03, 0.02),
)

#: Torso (thorax) and pelvis rings: height [m] relative to a landmark, forward offset [m],
#: half-width and half-depth [m]; then their rounded ends [m].
_TORSO = (
    (("c7", -0.015), -0.01, 0.065, 0.055),
    (("shoulder_r", 0.06), 0.0, 0.165, 0.075),
    (("shoulder_r", -0.03), 0.0, 0.19, 0.105),
    (("shoulder_r", -0.16), 0.015, 0.17, 0.125),
    (("l5s1", 0.12), 0.005, 0.15, 0.115),
    (("l5s1", 0.0), -0.005, 0.15, 0.11),
)
_TORSO_ENDS = (0.02, 0.01)
_PELVIS = (
    (("l5s1", 0.01), -0.01, 0.15, 0.11),
    (("hip_r", 0.0), -0.02, 0.172, 0.12),
    (("hip_r", -0.07), -0.025, 0.16, 0.11),
)
_PELVIS_ENDS = (0.01, 0.06)

#: The legs of the upper body, drawn for context: thigh and shank lengths, ankle height,
#: heel behind and toes ahead of the ankle [m] (the standing body's for ANSUR II's mean man).
_LEGS = (0.4130, 0.4151, 0.0729, 0.0543, 0.2169)

#: A seated upper body's stool [m]: the hip joint centres above its top (as
#: docs/problem-files.md's 0.55 m hips on a 0.46 m seat), its centre ahead of them, its
#: cushion's radius and thickness, its post's radius, its base's radius and thickness.
_STOOL = {
    "below_hips": 0.09,
    "forward": 0.04,
    "cushion": (0.2, 0.05),
    "post": 0.025,
    "base": (0.18, 0.03),
}

#: Neck (from C7 up), head and nose: centre offsets [m] (forward, up) and semi-axes [m]
#: (width, depth, height) of the head and nose.
_NECK = ((0.01, -0.03), (0.015, 0.1), 0.055, 0.06)
_HEAD = (-0.07, -0.115, (0.077, 0.1, 0.118))  # forward of the eyes, down from the vertex
_NOSE = ((0.03, -0.035), 0.018)  # from the eyes

#: A posture's colour mixed with white [0–1] for the task limbs and for the other parts;
#: the opacity of a translucent mannequin's fill (other parts, task limbs).
TASK_WHITE, IDLE_WHITE, OVERLAY_ALPHA = 0.1, 0.62, (0.15, 0.4)

#: The context parts' fill and outline.
CONTEXT = ("0.85", "0.6")

#: Landmarks a body needs for its mannequin.
NEEDED = ("c7", "vertex", "eyes", "shoulder_r", "shoulder_l", "l5s1", "hip_r", "hip_l")


@dataclass(frozen=True)
class Part:
    """A solid of the mannequin: ``rings`` (k × 3 × 3 [m]: centre, half-axis, other half-
    axis, world frame, zero posture) carried by ``dof``; ``limb`` names its limb ("right
    arm", ...) or is None for the head, neck, torso and pelvis; a ``context`` part (the
    legs and seat of a seated upper body) is not part of the model, only drawn."""

    name: str
    dof: str | None
    rings: np.ndarray
    limb: str | None = None
    context: bool = False

    def points(self) -> np.ndarray:
        """The rings' points (k × RING_POINTS × 3 [m], zero posture)."""
        angle = np.linspace(0.0, 2 * np.pi, RING_POINTS, endpoint=False)
        c, a, b = self.rings[:, 0, None], self.rings[:, 1, None], self.rings[:, 2, None]
        return c + a * np.cos(angle)[:, None] + b * np.sin(angle)[:, None]


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _solid(
    centres: np.ndarray,
    widths: Iterable[float],
    depths: Iterable[float],
    across: np.ndarray,
    ends: tuple[float, float],
    axis: np.ndarray | None = None,
) -> np.ndarray:
    """Rings through ``centres`` (k × 3), half-widths along ``across`` and half-depths
    perpendicular to it and to the ``axis`` (by default from the first centre to the
    last), each end rounded by a half-ellipsoid ``ends`` [m] long."""
    axis = _unit(centres[-1] - centres[0]) if axis is None else axis
    u = _unit(across - (across @ axis) * axis)
    v = np.cross(axis, u)
    rings = [np.array([c, w * u, d * v]) for c, w, d in zip(centres, widths, depths, strict=True)]

    def cap(ring: np.ndarray, length: float, angles: np.ndarray) -> list[np.ndarray]:
        return [
            np.array([ring[0] + length * np.sin(t) * axis, *np.cos(t) * ring[1:]]) for t in angles
        ]

    first = cap(rings[0], -ends[0], _CAP[::-1])
    return np.array([*first, *rings, *cap(rings[-1], ends[1], _CAP)])


def _ellipsoid(centre: np.ndarray, semi: tuple[float, float, float]) -> np.ndarray:
    """An upright ellipsoid: ``semi`` = half-width (y), half-depth (x), half-height [m]."""
    width, depth, height = semi
    return _solid(centre[None], (width,), (depth,), np.eye(3)[1], (height,) * 2, np.eye(3)[2])


def parts(body: BodyModel) -> list[Part]:
    """The mannequin of a human body, or no parts for a body without the landmarks of
    ``NEEDED`` (a planar arm: drawn as a stick figure)."""
    if not set(NEEDED) <= set(body.landmarks):
        return []
    at = {n: np.asarray(lm.position, dtype=float) for n, lm in body.landmarks.items()}
    carrier = {n: lm.dof for n, lm in body.landmarks.items()}
    s = np.linalg.norm(at["shoulder_r"] - at["shoulder_l"]) / REFERENCE_BIACROMIAL
    x, y, z = np.eye(3)

    def stack(rings: tuple, ends: tuple[float, float]) -> np.ndarray:
        centres = np.array(
            [[at[n][0] + s * dx, 0.0, at[n][2] + s * dz] for (n, dz), dx, _, _ in rings]
        )
        widths, depths = (s * np.array([r[k] for r in rings]) for k in (2, 3))
        return _solid(centres, widths, depths, y, (s * ends[0], s * ends[1]))

    neck_low, neck_high, neck_w, neck_d = _NECK
    neck = np.array([at["c7"] + s * (neck_low[0] * x + neck_low[1] * z),
                     at["c7"] + s * (neck_high[0] * x + neck_high[1] * z)])  # fmt: skip
    head_x, head_z, semi = _HEAD
    head = np.array([at["eyes"][0] + s * head_x, 0.0, at["vertex"][2] + s * head_z])
    (nose_x, nose_z), nose_r = _NOSE
    nose = at["eyes"] + s * (nose_x * x + nose_z * z)
    thorax, pelvis = carrier["c7"], carrier["hip_r"]
    found = [
        Part("torso", thorax, stack(_TORSO, _TORSO_ENDS)),
        Part("pelvis", pelvis, stack(_PELVIS, _PELVIS_ENDS)),
        Part("neck", thorax, _solid(neck, (s * neck_w,) * 2, (s * neck_d,) * 2, y, (0.02, 0.02))),
        Part("head", thorax, _ellipsoid(head, tuple(s * np.array(semi)))),
        Part("nose", thorax, _ellipsoid(nose, (s * nose_r,) * 3)),
    ]
    for segment in body.segments:
        kind, _, side = segment.name.rpartition("_")
        if kind in LIMBS and side in SIDES and segment.proximal and segment.distal:
            rings = _limb(kind, at[segment.proximal], at[segment.distal], s)
            found.append(Part(segment.name, segment.dof, rings, f"{SIDES[side]} {LIMBS[kind]}"))
    if pelvis is None and not any(part.limb and "leg" in part.limb for part in found):
        found = _seated(at, s) + found  # first: drawn behind a part as near
    return found


def _limb(kind: str, p0: np.ndarray, p1: np.ndarray, s: float) -> np.ndarray:
    """The rings of a limb segment of ``kind`` from ``p0`` to ``p1`` [m], sizes × ``s``."""
    y = np.eye(3)[1]
    if kind == "foot":
        fractions, heights, widths, depths, ends = _FOOT
        up = np.cross(_unit(p1 - p0), y)
        centres = [p0 + f * (p1 - p0) + s * h * up for f, h in zip(fractions, heights, strict=True)]
    else:
        fractions, widths, depths, ends = _SEGMENTS[kind]
        centres = [p0 + f * (p1 - p0) for f in fractions]
    return _solid(
        np.array(centres), s * np.array(widths), s * np.array(depths), y, (s * ends[0], s * ends[1])
    )


def _seated(at: dict[str, np.ndarray], s: float) -> list[Part]:
    """Legs under a pelvis held above the floor (the upper body), and a stool when they
    cannot stand straight: fixed, drawn for context only."""
    thigh, shank, ankle, heel, toe = s * np.array(_LEGS)
    x, y, z = np.eye(3)
    found = []
    for side in SIDES:
        hip = at[f"hip_{side}"]
        drop = float(np.clip(hip[2] - ankle - shank, -thigh, thigh))  # of the knee [m]
        knee = hip + np.sqrt(thigh**2 - drop**2) * x - drop * z
        sole = knee - knee[2] * z
        bones = {
            "thigh": (hip, knee),
            "shank": (knee, sole + ankle * z),
            "foot": (sole - heel * x, sole + toe * x),
        }
        found += [Part(f"{k}_{side}", None, _limb(k, *ends, s), context=True)
                  for k, ends in bones.items()]  # fmt: skip
    hip = (at["hip_r"] + at["hip_l"]) / 2
    seat = hip[2] - s * _STOOL["below_hips"]
    if hip[2] - ankle - shank >= thigh or seat <= _STOOL["base"][1]:
        return found
    centre = (hip[0] + _STOOL["forward"]) * x
    cushion = _STOOL["cushion"]
    pieces = {
        "seat": (seat - cushion[1], seat, cushion[0]),
        "post": (_STOOL["base"][1], seat - cushion[1], _STOOL["post"]),
        "base": (0.0, *_STOOL["base"][1::-1]),
    }
    for name, (low, high, radius) in pieces.items():
        ends = np.array([centre + low * z, centre + high * z])
        rings = _solid(ends, (radius,) * 2, (radius,) * 2, y, (0.0, 0.0))
        found.append(Part(name, None, rings, context=True))
    return found


def limbs_of(
    body: BodyModel, found: list[Part], landmarks: Iterable[str], segments: Iterable[str] = ()
) -> set[str]:
    """The limbs that carry any of ``landmarks`` (a task's effector, a load's point) or
    any of ``segments`` (an orientation task's): the limb of the first part carried by the
    landmark's frame or, failing one, by the nearest frame above it."""
    by_frame: dict[str | None, Part] = {}
    for part in found:
        if not part.context:
            by_frame.setdefault(part.dof, part)
    named = set(segments)
    limbs = {p.limb for p in found if p.name in named}
    for name in landmarks:
        chain = [None, *body.ancestors(body.landmarks[name].dof)]
        part = next((by_frame[f] for f in reversed(chain) if f in by_frame), None)
        limbs.add(part.limb if part is not None else None)
    return limbs - {None}


def hull(points: np.ndarray) -> np.ndarray:
    """The convex hull (counter-clockwise, h × 2) of points (m × 2), by Andrew's monotone
    chain."""
    ordered = sorted({(float(px), float(py)) for px, py in points})
    if len(ordered) < 3:
        return np.array(ordered)

    def half(chain: list[tuple[float, float]]) -> list[tuple[float, float]]:
        kept: list[tuple[float, float]] = []
        for p in chain:
            while len(kept) >= 2:
                (ax, ay), (bx, by) = kept[-2], kept[-1]
                if (bx - ax) * (p[1] - ay) - (by - ay) * (p[0] - ax) > 0:
                    break
                kept.pop()
            kept.append(p)
        return kept[:-1]

    return np.array(half(ordered) + half(ordered[::-1]))


def faces(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The surface of a part's ring points (k × n × 3 [m]): quadrilaterals between
    neighbouring rings ((k-1)·n × 4 × 3) and their outward unit normals."""
    nxt = np.roll(points, -1, axis=1)
    quads = np.stack([points[:-1], nxt[:-1], nxt[1:], points[1:]], axis=2).reshape(-1, 4, 3)
    normals = np.cross(quads[:, 2] - quads[:, 0], quads[:, 3] - quads[:, 1])
    centre = points.mean(axis=(0, 1))  # the parts are convex: outward is away from it
    outward = np.einsum("ij,ij->i", normals, quads.mean(axis=1) - centre)
    normals *= np.sign(outward + (outward == 0))[:, None]
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return quads, normals / np.where(length > 0, length, 1.0)


def tint(colour: object, white: float) -> np.ndarray:
    """``colour`` mixed with white (``white`` 0: the colour, 1: white), RGB."""
    rgb = np.asarray(to_rgb(colour))
    return rgb + (1.0 - rgb) * white


def fill(colour: object, task: bool, solid: bool) -> np.ndarray:
    """The fill (RGBA) of a part of a task limb or not, of a solid mannequin or not."""
    alpha = 1.0 if solid else OVERLAY_ALPHA[task]
    return np.r_[tint(colour, TASK_WHITE if task else IDLE_WHITE), alpha]


def swatch(colour: object, solid: bool, label: str) -> Patch:
    """A legend entry of a mannequin's colour and opacity."""
    return Patch(fc=fill(colour, False, solid), ec=colour, lw=1.0, label=label)


class Mannequin:
    """A skeleton's mannequin drawn in ``ax``: in a view of two world ``axes`` each part a
    filled outline, the nearer over the farther, in 3-D (three axes) a shaded surface. A
    ``solid`` mannequin is opaque, another translucent in opaque outlines; the ``task``
    limbs take a deeper shade of the colour than the rest; the context parts are grey, and
    drawn by a solid mannequin only. ``layer`` is its zorder."""

    def __init__(
        self,
        ax: Axes,
        skeleton: Skeleton,
        axes: list[int],
        *,
        task: set[str],
        solid: bool,
        layer: float,
        colour: object,
    ) -> None:
        self.ax, self.skeleton, self.axes = ax, skeleton, axes
        self.solid, self.layer, self.colour = solid, layer, colour
        self.shown = [k for k, part in enumerate(skeleton.parts) if solid or not part.context]
        self.task = [skeleton.parts[k].limb in task for k in self.shown]
        self.context = [skeleton.parts[k].context for k in self.shown]
        self.three = len(axes) == 3
        self.patches = [] if self.three else [
            ax.add_patch(Polygon(np.zeros((3, 2)), closed=True, gid=f"body:{part.name}"))
            for part in (skeleton.parts[k] for k in self.shown)
        ]  # fmt: skip
        self.surface: Poly3DCollection | None = None
        self.step: int | None = None
        self.recolour(colour)

    def fills(self) -> np.ndarray:
        """The fill of every part drawn (parts × RGBA)."""
        return np.array(
            [
                to_rgba(CONTEXT[0]) if context else fill(self.colour, task, self.solid)
                for task, context in zip(self.task, self.context, strict=True)
            ]
        )

    def recolour(self, colour: object) -> None:
        """Draw the mannequin in another colour."""
        self.colour = colour
        width = 0.8 if self.solid else 1.0
        for patch, face, context in zip(self.patches, self.fills(), self.context, strict=False):
            patch.set_facecolor(face)
            patch.set_edgecolor(CONTEXT[1] if context else colour)
            patch.set_linewidth(width)
        if self.step is not None:
            self.update(self.step)

    def update(self, step: int) -> None:
        """Move the parts to the posture at ``step``."""
        self.step = step
        every = self.skeleton.solids(step)
        solids = [every[k] for k in self.shown]
        if self.three:
            self._surface(solids)
            return
        i, j = self.axes
        toward = np.cross(np.eye(3)[i], np.eye(3)[j])  # toward the viewer
        depth = [round(float(points.mean(axis=(0, 1)) @ toward), 3) for points in solids]
        order = np.argsort(depth, kind="stable")  # within 1 mm, in the parts' order
        for rank, k in enumerate(order):
            self.patches[k].set_xy(hull(solids[k][..., [i, j]].reshape(-1, 2)))
            self.patches[k].set_zorder(self.layer + 0.001 * rank)

    def _surface(self, solids: list[np.ndarray]) -> None:
        if self.surface is not None:
            self.surface.remove()
        elevation, azimuth = np.radians([self.ax.elev, self.ax.azim])
        eye = np.array(
            [
                np.cos(elevation) * np.cos(azimuth),
                np.cos(elevation) * np.sin(azimuth),
                np.sin(elevation),
            ]
        )
        light = eye + np.array([0.0, 0.0, 0.7])
        light /= np.linalg.norm(light)
        quads, colours = [], []
        for points, fill in zip(solids, self.fills(), strict=True):
            part_quads, normals = faces(points)
            bright = 0.45 + 0.55 * np.clip(normals @ light, 0.0, 1.0)
            shaded = np.c_[fill[None, :3] * bright[:, None], np.full(len(bright), fill[3])]
            quads.append(part_quads)
            colours.append(shaded)
        colour = np.concatenate(colours)
        self.surface = Poly3DCollection(
            np.concatenate(quads), facecolors=colour, edgecolors=colour, linewidths=0.2
        )
        self.surface.set_zorder(self.layer)
        self.surface.set_gid("mannequin")
        self.ax.add_collection3d(self.surface)
