"""docs/low_back.md and docs/sensitivity.md: the inputs that move a problem's L5/S1
compression most, as ``casadi-posture sensitivity`` ranks them
(``compression-sensitivity problem=PATH top=KEY,KEY,...``)."""

from __future__ import annotations

from typing import Any

import casadi_posture as cp
from casadi_posture.sensitivity_analysis.analysis import sensitivity

from . import parallel
from .regions import Region
from .session import ROOT, Session


def ranking(path: str) -> dict[str, Any]:
    """The compression [N] of the shipped problem at ``path`` at the IK's posture and its
    ``ranked`` inputs: (key, elasticity) pairs, largest elasticity first."""
    found = sensitivity(cp.load(ROOT / path))
    rows = found.ranked_compression()
    return {
        "compression_N": found.compression,
        "ranked": [(str(r["key"]), float(r["compression_elasticity"] or 0.0)) for r in rows],
    }


def values(region: Region, session: Session) -> dict[str, Any]:
    """``compression_N`` [N] of the problem and ``top``, the elasticities of its first
    inputs ranked (to 0.1, signed, typographic minus); raises ``ValueError`` unless those
    inputs are the keys of ``top=`` (in any order among equal elasticities), as the prose
    names them."""
    path = region.args["problem"]
    found = parallel.compute(ranking, [(path,)])[path,]
    top = region.args.get("top", "").split(",") if region.args.get("top") else []
    ranked = dict(found["ranked"])
    first = [key for key, _ in found["ranked"][: len(top)]]
    sizes = [round(abs(ranked.get(key, 0.0)), 9) for key in top]
    if sorted(first) != sorted(top) or sizes != sorted(sizes, reverse=True):
        raise ValueError(f"the first inputs ranked are {first}, not {top} as the prose says")
    return {
        "compression_N": found["compression_N"],
        "top": [f"{value:+.1f}".replace("-", "−") for _, value in found["ranked"][: len(top)]],
    }
