"""LIBERO-10's study (STUDY_SCENE1: the book into the caddy's back compartment): LIBERO's
`Libero_Study_Tabletop_Manipulation` problem, a desk that its scene file holds (no table arena: its
top at 0.88513 m, where its collision box ends), the Panda on its Rethink mount 0.25 m behind the
desk's near half (`MountedPanda`), and everything on the desk 0.2 m nearer the robot than on
LIBERO's other tables (the problem's workspace offset): the regions, the desk caddy (turned half
about) and LIBERO's agentview camera.

Every value here is LIBERO's, from libero/libero/envs/problems/libero_study_tabletop_manipulation.py,
envs/robots/mounted_panda.py and the task's BDDL file; tests/libero/test_libero_10.py compares the
compiled scene with LIBERO's own environment. Its suite is LIBERO-10's,
whose tasks span several worlds: `scenes` says which this one stands.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from core import libero
from core.worlds import Camera, Placed
from core.worlds.libero_10_kitchen_scene3 import KITCHEN

SHIFT = -0.2  # the problem's workspace offset in x: where its regions and fixtures stand, against LIBERO's other tables
DESK_TOP = 0.88513

WORLD = replace(
    KITCHEN,
    name="libero_10_study",
    scenes=("STUDY_SCENE1_",),
    surface_z=DESK_TOP,
    reach=(-0.3 + SHIFT, 0.25 + SHIFT, -0.35, 0.35),
    robot_base=(-0.75, 0.0, 0.0),  # MountedPanda.base_xpos_offset["study_table"](1.0); the mount lifts it
    agentview=Camera(
        pos=(0.4586131746834771, 0.0, 1.6103500240372423),
        quat=(0.6380177736282349, 0.3048497438430786, 0.30484986305236816, 0.6380177736282349),
    ),
    arena={
        "scene": "scenes/libero_study_base_style.xml",
        "floor": "light-gray-floor-tile.png",
        "wall": "light-gray-plaster.png",
    },
    table=None,
    fixtures=(Placed(libero.FIXTURES["desk_caddy"], "desk_caddy_1", (-0.2 + SHIFT, -0.14, 0.887), float(np.pi)),),
)
