"""casadi_posture: how a posture changes as muscles tire (Rodriguez & Boulic 2008) on CasADi."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("casadi_posture")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"
