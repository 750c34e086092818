"""``python -m casadi_posture.cli``."""

from ..console import main

main()
