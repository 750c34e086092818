"""The ``casadi-posture`` entry point: Ctrl-C at any moment, even while the libraries a
command needs are loading, ends with one line and exit code 130, never a traceback."""

from __future__ import annotations

import sys

from casadi_posture.interrupt import EXIT_CODE


def main() -> None:
    try:
        from casadi_posture.cli import main as commands

        commands()
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        sys.exit(EXIT_CODE)
