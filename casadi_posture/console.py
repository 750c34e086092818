"""The ``casadi-posture`` entry point: Ctrl-C at any moment, even while the libraries a
command needs are loading, ends with one line and exit code 130, never a traceback.

The imports make objects that are kept to the end (modules, classes, functions) and almost
no garbage: the cyclic garbage collector is off while they run (its passes took a tenth of
their 0.8 s) and leaves what they made out of its later passes (``gc.freeze``: a full pass
over it took 0.05 s of a 20-minute run and 0.15 s of writing its files)."""

from __future__ import annotations

import gc
import sys

from casadi_posture.interrupt import EXIT_CODE


def main() -> None:
    try:
        gc.disable()
        from casadi_posture.cli import main as commands

        gc.freeze()
        gc.enable()
        commands()
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        sys.exit(EXIT_CODE)
