"""Commented problem files to start from (``casadi-posture init``)."""

from __future__ import annotations

from importlib import resources

#: Template name -> what it sets up.
TEMPLATES = {
    "hold": "a load held with the wrist on a line, the paper's holding experiment",
    "elbow": "only the elbow moves, with its torques over the range (the paper's Fig. 3)",
    "tree": "a body of your own: a 3-DOF arm described in the file, holding 1 kg at a point",
    "shelf": "a standing person holding a 4 kg box with both hands at a shelf",
    "seated": "a seated person holding a 1 kg part on a table with the right hand",
}


def template(name: str) -> str:
    """The text of template ``name`` (a key of ``TEMPLATES``)."""
    return resources.files(__name__).joinpath(f"{name}.toml").read_text("utf-8")
