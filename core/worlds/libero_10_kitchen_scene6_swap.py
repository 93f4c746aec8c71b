"""LIBERO-10's KITCHEN_SCENE6 as LIBERO-PRO's `libero_10_swap` lays it out: the microwave and the white
mug trade regions (the microwave on the table's right, near the robot; the mug where the microwave
stood). The rest is core/worlds/libero_10_kitchen_scene6.py's. The microwave stands at the centre of
the region PRO's BDDL file names for it (LIBERO draws it within 2.5 cm of it, turned as before);
tests/libero/test_libero_pro.py compares it with that file.
"""

from __future__ import annotations

from dataclasses import replace

from core import libero
from core.worlds import Placed, libero_10_kitchen_scene6

WORLD = replace(
    libero_10_kitchen_scene6.WORLD,
    name="libero_10_kitchen_scene6_swap",
    pro_suite="libero_10_swap",
    fixtures=(Placed(libero.FIXTURES["microwave"], "microwave_1", (-0.1, -0.25, 0.92)),),
)
