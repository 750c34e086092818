"""A document's working folder: its commands run there, in the document's order."""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

#: The repository's top folder.
ROOT = Path(__file__).resolve().parents[2]


class Session:
    """A fresh folder holding a copy of ``problems/``, as a reader's clone does; every
    region of one document runs in the same folder, so a file the tutorial's first
    command writes is there for the next one. Removed when the document is done."""

    def __init__(self) -> None:
        self._folder: tempfile.TemporaryDirectory[str] | None = None

    @property
    def folder(self) -> Path:
        """The working folder, made on first use."""
        if self._folder is None:
            self._folder = tempfile.TemporaryDirectory(prefix="docs-generate-")
            shutil.copytree(ROOT / "problems", Path(self._folder.name) / "problems")
        return Path(self._folder.name)

    @contextmanager
    def inside(self) -> Iterator[Path]:
        """The working folder as the current one, for the duration of the block."""
        before = Path.cwd()
        os.chdir(self.folder)
        try:
            yield self.folder
        finally:
            os.chdir(before)

    def close(self) -> None:
        """Remove the folder and everything the document's commands wrote."""
        if self._folder is not None:
            self._folder.cleanup()
            self._folder = None
