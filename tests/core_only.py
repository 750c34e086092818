"""``casadi-posture`` as the core install runs it: ``python tests/core_only.py ARGS...``.

The optional extras' packages (pyproject.toml's ``pandas``, ``parquet``, ``dask`` and
``motion``) are hidden from every import, even where they are installed, as on a machine
where only ``pip install casadi_posture`` was run. The environment variable
``HIDE_ALSO`` (comma-separated) hides more, to see a command lose a core package."""

from __future__ import annotations

import os
import sys
from importlib.abc import MetaPathFinder

#: The top-level modules of the optional extras' packages.
HIDDEN = frozenset({"pandas", "pyarrow", "dask", "distributed", "ezc3d", "bvhio"}) | frozenset(
    filter(None, os.environ.get("HIDE_ALSO", "").split(","))
)


class Hidden(MetaPathFinder):
    """Refuses to find a hidden module, as when it is not installed."""

    def find_spec(self, name: str, path=None, target=None):
        if name.partition(".")[0] in HIDDEN:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None


if __name__ == "__main__":
    sys.meta_path.insert(0, Hidden())
    sys.argv[0] = "casadi-posture"
    from casadi_posture.console import main

    main()
