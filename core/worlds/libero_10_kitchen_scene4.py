"""LIBERO-10's KITCHEN_SCENE4 (put the black bowl in the bottom drawer of the cabinet and close
it): LIBERO's kitchen (core/worlds/libero_10_kitchen_scene3.py) with the white cabinet and the wine
rack (turned half about) where this scene's regions stand them, the black bowl and the wine bottle.

Every value here is LIBERO's, from the task's BDDL file (the wine rack's body stands higher than
the cabinet's: LIBERO's placement puts it there, as in LIBERO-Goal); tests/libero/test_libero_10.py
compares the compiled scene with LIBERO's own environment.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from core import libero
from core.worlds import Placed, libero_spatial
from core.worlds.libero_10_kitchen_scene3 import KITCHEN

WORLD = replace(
    KITCHEN,
    name="libero_10_kitchen_scene4",
    scenes=("KITCHEN_SCENE4_",),
    fixtures=(
        Placed(libero.FIXTURES["white_cabinet"], "white_cabinet_1", (0.0, 0.3, libero_spatial.FIXTURE_Z)),
        Placed(libero.FIXTURES["wine_rack"], "wine_rack_1", (-0.1, -0.3, 0.92), float(np.pi)),
    ),
)
