"""A pinocchio model rebuilt from ``casadi-posture describe --json`` alone (shared by the
pinocchio cross-checks; pinocchio is imported when a model is built)."""

from __future__ import annotations

from typing import Any

import numpy as np


def pinocchio_model(model: dict[str, Any]) -> tuple[Any, list[str]]:
    """The fixed-base pinocchio model of a described body and its DOF names in order.

    Each DOF is a revolute joint about its axis at its origin (every frame is aligned with
    the world at the zero posture); segments and held loads are point masses on the DOF
    that carries them. Masses fixed to the world (no ``dof``) are left out: they take no
    joint torque.
    """
    import pinocchio as pin

    pm = pin.Model()
    pm.gravity.linear = np.array([0.0, 0.0, -model["gravity_m_s2"]])
    joint_id, origin = {None: 0}, {None: np.zeros(3)}
    for dof in model["dofs"]:
        parent = dof.get("parent")
        placement = pin.SE3(np.eye(3), np.array(dof["origin_m"]) - origin[parent])
        joint = pin.JointModelRevoluteUnaligned(np.array(dof["axis"]))
        joint_id[dof["name"]] = pm.addJoint(joint_id[parent], joint, placement, dof["name"])
        origin[dof["name"]] = np.array(dof["origin_m"])
    masses = [(s.get("dof"), s["mass_kg"], s["com_m"]) for s in model["segments"]]
    masses += [(ld["dof"], ld["mass_kg"], ld["point_m"]) for ld in model["loads"]]
    for dof, mass, point in masses:
        if dof is not None:
            lever = np.array(point) - origin[dof]
            pm.appendBodyToJoint(
                joint_id[dof], pin.Inertia(mass, lever, np.zeros((3, 3))), pin.SE3.Identity()
            )
    return pm, [d["name"] for d in model["dofs"]]
