"""LIBERO-10's KITCHEN_SCENE8 (put both moka pots on the stove): LIBERO's kitchen (core/worlds/
libero_10_kitchen_scene3.py) with the flat stove where this scene's region stands it, and two moka pots.

Every value here is LIBERO's, from the task's BDDL file; tests/libero/test_libero_10.py compares the
compiled scene with LIBERO's own environment.
"""

from __future__ import annotations

from dataclasses import replace

from core import libero
from core.worlds import Placed, libero_spatial
from core.worlds.libero_10_kitchen_scene3 import KITCHEN

WORLD = replace(
    KITCHEN,
    name="libero_10_kitchen_scene8",
    scenes=("KITCHEN_SCENE8_",),
    fixtures=(Placed(libero.FIXTURES["flat_stove"], "flat_stove_1", (-0.2, -0.2, libero_spatial.FIXTURE_Z)),),
)
