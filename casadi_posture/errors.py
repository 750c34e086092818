"""The one exception family of casadi_posture; every message names what to fix."""

from __future__ import annotations

from pathlib import Path
from typing import Any

#: The value of a key that has no single value to show: absent, or a whole table.
MISSING = object()


class CasadiPostureError(Exception):
    """Base of every error the library raises on purpose."""


class ProblemError(CasadiPostureError):
    """Bad input: names the file, the key, the value and what was expected."""

    def __init__(self, file: str | Path | None, key: str | None, value: Any, expected: str) -> None:
        self.file = str(file) if file is not None else None
        self.key = key
        self.value = value
        self.expected = expected
        super().__init__(self._message())

    def _message(self) -> str:
        where = f"{self.file}: " if self.file else ""
        if self.key is None:
            return f"{where}{self.expected}"
        if self.value is MISSING:
            return f"{where}{self.key}: expected {self.expected}"
        return f"{where}{self.key} = {_show(self.value)}: expected {self.expected}"


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."
