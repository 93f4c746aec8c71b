"""LIBERO-10's KITCHEN_SCENE6 (put the yellow and white mug in the microwave and close it): LIBERO's
kitchen (core/worlds/libero_10_kitchen_scene3.py) with the microwave where this scene's region
stands it, the yellow and white mug and the white mug.

Every value here is LIBERO's, from the task's BDDL file (the microwave's body stands as high as the
wine rack's: its model's bottom site is as low); tests/libero/test_libero_10.py compares the
compiled scene with LIBERO's own environment.
"""

from __future__ import annotations

from dataclasses import replace

from core import libero
from core.worlds import Placed
from core.worlds.libero_10_kitchen_scene3 import KITCHEN

WORLD = replace(
    KITCHEN,
    name="libero_10_kitchen_scene6",
    scenes=("KITCHEN_SCENE6_",),
    fixtures=(Placed(libero.FIXTURES["microwave"], "microwave_1", (0.0, 0.35, 0.92)),),
)
