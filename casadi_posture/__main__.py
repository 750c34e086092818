"""``python -m casadi_posture``: the command line."""

from casadi_posture.console import main

main()
