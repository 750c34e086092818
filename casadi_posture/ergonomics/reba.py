"""The REBA worksheet (Hignett & McAtamney 2000, Applied Ergonomics 31:201-205) as pure
functions: the step scores of the trunk, neck and legs and of one side's arm, the posture
scores from Tables A and B, scores A and B with load and coupling, the Table C score, the
activity score and the REBA score with its action and risk level. Tables, bands and their
sources: ``data/rula_reba.toml``, docs/rula_reba.md."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Literal

from casadi_posture.ergonomics.rula import band, check_finite, clip, interval, value

Coupling = Literal["good", "fair", "poor", "unacceptable"]
COUPLINGS: tuple[Coupling, ...] = ("good", "fair", "poor", "unacceptable")


@dataclass(frozen=True)
class RebaInputs:
    """The posture and task for REBA, with one side's arm. Angles [deg]: trunk flexion (+)
    or extension (−) from the vertical; neck flexion (+) or extension (−) from the trunk;
    knee flexion (the larger of the two knees); upper arm flexion (+) or extension (−) from
    the trunk; elbow flexion (0 = straight); wrist flexion (+) or extension (−).
    ``load_kg`` [kg] is the load or force handled."""

    upper_arm_deg: float
    lower_arm_deg: float
    wrist_deg: float = 0.0
    trunk_deg: float = 0.0
    trunk_twisted_or_side_bent: bool = False
    neck_deg: float = 0.0
    neck_twisted_or_side_bent: bool = False
    bilateral_weight_bearing: bool = True
    knee_deg: float = 0.0
    seated: bool = False
    load_kg: float = 0.0
    shock: bool = False
    arm_abducted_or_rotated: bool = False
    shoulder_raised: bool = False
    arm_supported: bool = False
    wrist_deviated_or_twisted: bool = False
    coupling: Coupling = "good"
    static: bool = False
    repeated: bool = False
    rapid_changes: bool = False

    def __post_init__(self) -> None:
        check_finite(self)
        if self.coupling not in COUPLINGS:
            raise ValueError(f"coupling = {self.coupling!r}: one of {', '.join(COUPLINGS)}")


@dataclass(frozen=True)
class RebaResult:
    """Every score of the worksheet, the REBA score (1-15), its action level (0-4) and the
    risk and action the paper names."""

    neck: int
    trunk: int
    legs: int
    posture_a: int
    load: int
    score_a: int
    upper_arm: int
    lower_arm: int
    wrist: int
    posture_b: int
    coupling: int
    score_b: int
    table_c: int
    activity: int
    reba: int
    action_level: int
    risk: str
    action: str

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def trunk(x: RebaInputs) -> int:
    """1 upright, else the band of the trunk's angle from the vertical; +1 twisted or
    side-bent."""
    if abs(x.trunk_deg) <= value("neutral_tolerance"):
        score = int(value("reba.trunk.upright"))
    else:
        score = band(x.trunk_deg, "reba.trunk")
    return clip(score + int(x.trunk_twisted_or_side_bent), 1, 5)


def neck(x: RebaInputs) -> int:
    """The band of the neck's flexion, 2 in extension; +1 twisted or side-bent."""
    if x.neck_deg < -value("neutral_tolerance"):
        score = int(value("reba.neck.extension"))
    else:
        score = band(max(x.neck_deg, 0.0), "reba.neck")
    return clip(score + int(x.neck_twisted_or_side_bent), 1, 3)


def legs(x: RebaInputs) -> int:
    """1 bilateral weight bearing (or walking, sitting), 2 if not; + the knees' band when
    standing."""
    score = int(value("reba.legs.base")[0 if x.bilateral_weight_bearing else 1])
    if not x.seated:
        knee = interval(x.knee_deg, value("reba.legs.knee_edges"), value("reba.legs.knee_on_edge"))
        score += int(value("reba.legs.knee_scores")[knee])
    return clip(score, 1, 4)


def load(x: RebaInputs) -> int:
    """The load's band, +1 for a shock or a rapid build-up of force."""
    i = interval(x.load_kg, value("reba.load.edges_kg"), value("reba.load.on_edge"))
    return int(value("reba.load.scores")[i]) + (int(value("reba.load.shock")) if x.shock else 0)


def upper_arm(x: RebaInputs) -> int:
    """The band of the upper arm's angle, +1 abducted or rotated, +1 raised, −1 supported."""
    score = band(x.upper_arm_deg, "reba.upper_arm")
    score += int(x.arm_abducted_or_rotated) + int(x.shoulder_raised) - int(x.arm_supported)
    return clip(score, 1, 6)


def lower_arm(x: RebaInputs) -> int:
    """The band of the elbow's flexion."""
    return band(x.lower_arm_deg, "reba.lower_arm")


def wrist(x: RebaInputs) -> int:
    """The band of the flexion's or extension's size, +1 deviated or twisted."""
    return clip(band(abs(x.wrist_deg), "reba.wrist") + int(x.wrist_deviated_or_twisted), 1, 3)


def activity(x: RebaInputs) -> int:
    """+1 each: a body part static, small actions repeated, rapid large changes."""
    return int(value("reba.activity")) * (int(x.static) + int(x.repeated) + int(x.rapid_changes))


def action_level(reba: int) -> tuple[int, str, str]:
    """The action level (0-4) of a REBA score, the risk and the action the paper names."""
    uppers = value("reba.action_levels.upper_scores")
    level = next((i for i, top in enumerate(uppers) if reba <= top), len(uppers) - 1)
    risk, action = value("reba.action_levels.risks"), value("reba.action_levels.actions")
    return level, str(risk[level]), str(action[level])


def score(x: RebaInputs) -> RebaResult:
    """The whole worksheet: every intermediate score and the REBA score."""
    nk, tr, lg = neck(x), trunk(x), legs(x)
    posture_a = int(value("reba.table_a")[tr - 1][nk - 1][lg - 1])
    force = load(x)
    ua, la, wr = upper_arm(x), lower_arm(x), wrist(x)
    posture_b = int(value("reba.table_b")[ua - 1][la - 1][wr - 1])
    coupling = int(value("reba.coupling")[COUPLINGS.index(x.coupling)])
    score_a, score_b = posture_a + force, posture_b + coupling
    table = value("reba.table_c")
    table_c = int(table[min(score_a, len(table)) - 1][min(score_b, len(table[0])) - 1])
    act = activity(x)
    reba = table_c + act
    level, risk, action = action_level(reba)
    return RebaResult(
        nk, tr, lg, posture_a, force, score_a, ua, la, wr, posture_b, coupling, score_b,
        table_c, act, reba, level, risk, action,
    )  # fmt: skip
