"""A body tree as a problem file describes it (``body.tree``): its cross-references checked
with the file's keys, then built into a ``BodyModel`` (docs/problem-files.md)."""

from __future__ import annotations

import math
from pathlib import Path

from casadi_posture.body.tree import REGIONS, BodyModel, Dof, Foot, Landmark, Segment
from casadi_posture.errors import ProblemError
from casadi_posture.spec.schema import TreeSpec


def check_tree(tree: TreeSpec, path: Path, key: str = "body.tree") -> None:
    """Refuse a tree whose names repeat or whose references point nowhere: parents defined
    before their children, segments and landmarks carried by DOFs of the tree, muscle
    groups in a joint region of ``REGIONS``."""
    dofs: set[str] = set()
    for i, dof in enumerate(tree.dofs):
        where = f"{key}.dofs[{i}]"
        if dof.name in dofs:
            raise ProblemError(path, f"{where}.name", dof.name, "a name no other DOF has")
        if dof.parent is not None and dof.parent not in dofs:
            expected = f"a DOF listed before it (parents first): one of {sorted(dofs)}"
            raise ProblemError(path, f"{where}.parent", dof.parent, expected)
        dofs.add(dof.name)
    groups: set[str] = set()
    for i, dof in enumerate(tree.dofs):
        for side in ("positive", "negative"):
            name, region = getattr(dof, side).name, getattr(dof, side).region
            if name in groups:
                raise ProblemError(
                    path, f"{key}.dofs[{i}].{side}.name", name, "a name no other half-joint has"
                )
            if region not in REGIONS:
                expected = f"a joint region: one of {list(REGIONS)}"
                raise ProblemError(path, f"{key}.dofs[{i}].{side}.region", region, expected)
            groups.add(name)
    tables = (("segments", tree.segments), ("landmarks", tree.landmarks), ("feet", tree.feet))
    for table, items in tables:
        names: set[str] = set()
        for i, item in enumerate(items):
            where = f"{key}.{table}[{i}]"
            if item.name in names:
                raise ProblemError(path, f"{where}.name", item.name, "a name no other has")
            names.add(item.name)
            if item.dof is not None and item.dof not in dofs:
                expected = f"a DOF of the tree (or none: fixed to the world): one of {sorted(dofs)}"
                raise ProblemError(path, f"{where}.dof", item.dof, expected)
    landmarks = {lm.name for lm in tree.landmarks}
    for i, segment in enumerate(tree.segments):
        for end in ("proximal", "distal"):
            name = getattr(segment, end)
            if name is not None and name not in landmarks:
                raise ProblemError(
                    path,
                    f"{key}.segments[{i}].{end}",
                    name,
                    f"a landmark: one of {sorted(landmarks)}",
                )
    if len(tree.feet) == 2 and sum(f.dof is None for f in tree.feet) != 1:
        dofs_of_feet = [f.dof for f in tree.feet]
        expected = "two feet: the tree's root foot (no dof) and one carried by a DOF"
        raise ProblemError(path, f"{key}.feet", dofs_of_feet, expected)
    if sum(s.mass_kg for s in tree.segments) <= 0:
        raise ProblemError(path, f"{key}.segments", "total mass 0 kg", "a body with mass")


def body_from_tree(tree: TreeSpec, gravity: float) -> BodyModel:
    """The kinematic tree of a checked ``body.tree``; ``gravity`` [m/s²]."""
    dofs = [
        Dof(
            d.name,
            d.parent,
            tuple(d.origin_m),
            tuple(d.axis),
            math.radians(d.range_deg[0]),
            math.radians(d.range_deg[1]),
            d.positive.name,
            d.negative.name,
            (d.positive.region, d.negative.region),
        )
        for d in tree.dofs
    ]
    segments = [
        Segment(s.name, s.dof, s.mass_kg, tuple(s.com_m), s.proximal, s.distal)
        for s in tree.segments
    ]
    landmarks = [Landmark(lm.name, lm.dof, tuple(lm.position_m)) for lm in tree.landmarks]
    feet = [Foot(f.name, f.dof, tuple(tuple(p) for p in f.outline_m)) for f in tree.feet]
    return BodyModel(tree.name, dofs, segments, landmarks, gravity=gravity, feet=feet)
