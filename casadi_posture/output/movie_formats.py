"""The animation formats and whether this machine can write one (checked before a run,
without importing the drawing modules)."""

from __future__ import annotations

from casadi_posture.errors import ProblemError

#: Animation formats and the matplotlib writer of each.
WRITERS = {"gif": "pillow", "mp4": "ffmpeg"}


def check_format(name: str, key: str = "--animate") -> str:
    """An animation format this machine can write (gif always; mp4 needs ffmpeg)."""
    from matplotlib import animation  # only when an animation is asked for

    if name not in WRITERS:
        raise ProblemError(None, key, name, f"one of {', '.join(WRITERS)}")
    if not animation.writers.is_available(WRITERS[name]):
        expected = "gif (mp4 needs an ffmpeg program on the PATH, and none was found)"
        raise ProblemError(None, key, name, expected)
    return name
