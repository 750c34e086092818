"""``python -m casadi_posture.cli``."""

import sys

from . import main

sys.exit(main())
