"""Deconfounded robot-manipulation datasets: `python -m gen referent=<type> n=<episodes>`."""

import oracle  # noqa: F401  (sets headless-rendering defaults before anything imports mujoco)

__version__ = "0.1.0"
