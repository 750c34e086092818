"""Whether the file system lets a command write its output where it was told to, asked of
the file system itself before anything runs: a path that cannot be written is one line
naming it and the file system's reason, not an error half-way through a run."""

from __future__ import annotations

import errno
import os
import tempfile
from pathlib import Path

from casadi_posture.errors import ProblemError


def check_writable(path: Path, key: str = "--out", *, folder: bool = True) -> None:
    """Refuse an output ``path`` (a ``folder`` to create or fill, else a file) the file
    system will not let us write: a parent that is a file, a name too long, a dangling
    symbolic link or a loop of them, a folder that refuses new files (read-only, not ours,
    ``/proc``); ``ProblemError`` naming ``key``, the path and the reason."""
    reason = refusal(path, folder=folder)
    if reason is not None:
        what = "folder" if folder else "file"
        raise ProblemError(None, key, str(path), f"a {what} the file system can write ({reason})")


def refusal(path: Path, *, folder: bool = True) -> str | None:
    """Why the file system will not let us write ``path`` (None: it will), found by walking
    its parts from the first and by creating (and removing) a folder where the first new
    part would go."""
    parts = path.parts
    for count in range(1, len(parts) + 1):
        here = Path(*parts[:count])
        last = count == len(parts)
        try:
            here.stat()
        except FileNotFoundError:
            if here.is_symlink():
                return f"{here} is a symbolic link to {os.readlink(here)}, which does not exist"
            return _creatable(here.parent)
        except OSError as error:
            return _reason(here, error)
        if not last and not here.is_dir():
            return f"{here} is a file, not a folder"
    if path.is_dir() != folder:
        is_a, wanted = ("file", "folder") if folder else ("folder", "file")
        return f"{path} is a {is_a}, not a {wanted}"
    if not folder and not os.access(path, os.W_OK):
        return f"{path} cannot be written over (permission denied)"
    return _creatable(path if folder else path.parent)


def _creatable(parent: Path) -> str | None:
    """Why nothing can be created in the existing folder ``parent`` (None: it can)."""
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".casadi-posture-check-", dir=parent))
    except OSError as error:
        return f"{parent} refuses new files: {error.strerror}"
    return None


def _reason(here: Path, error: OSError) -> str:
    """The file system's reason ``error`` for ``here``, in words a user can act on."""
    if error.errno == errno.ENAMETOOLONG:
        longest = max(len(part.encode()) for part in here.parts)
        most = _longest_name(here.parent)
        if longest > most:
            return f"a name of {longest} bytes: the file system takes at most {most}"
        return f"a path of {len(os.fsencode(here))} bytes: longer than the file system takes"
    if error.errno == errno.ELOOP:
        return f"{here} is a loop of symbolic links"
    if error.errno == errno.ENOTDIR:
        return f"{here.parent} is a file, not a folder"
    return f"{here}: {error.strerror}"


def _longest_name(folder: Path) -> int:
    """The longest name [bytes] the file system of ``folder`` takes (255 if it will not say)."""
    try:
        return os.pathconf(folder, "PC_NAME_MAX")
    except (OSError, ValueError):
        return 255
