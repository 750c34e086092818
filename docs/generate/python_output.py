"""A Python example and what it prints: the region holds a ```python block and the ```text
block after it; the code is run in the document's working folder and the text block
rewritten with its output."""

from __future__ import annotations

import re
import subprocess
import sys

from .regions import Region
from .session import Session

EXAMPLE = re.compile(r"\A(```python\n.*?```\n)\n```text\n.*?```\n?\Z", re.DOTALL)


def generate(region: Region, session: Session) -> str:
    """The code block unchanged, then what it prints today."""
    match = EXAMPLE.match(region.body)
    if match is None:
        raise ValueError("a python-output region holds a ```python block and a ```text block")
    code = match[1].removeprefix("```python\n").removesuffix("```\n")
    ran = subprocess.run(
        [sys.executable, "-c", code], cwd=session.folder, capture_output=True, text=True
    )
    if ran.returncode != 0:
        raise RuntimeError(f"the example failed:\n{ran.stderr}")
    return f"{match[1]}\n```text\n{ran.stdout.rstrip()}\n```"
