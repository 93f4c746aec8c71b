"""LIBERO-10's living room (LIVING_ROOM_SCENE1, 2, 5 and 6: the groceries and the basket, the mugs
and the plates): LIBERO's `Libero_Living_Room_Tabletop_Manipulation` problem, a living-room table
that its scene file holds (no table arena: its top at 0.437 m, where its collision boxes end), the
Panda standing on the floor without a mount at the table's edge (`OnTheGroundPanda`, its base
lifted to 0.42 m), and its own agentview camera, low over the table with LIBERO-Object's turn. The
four scenes stand no furniture, so one world holds them all; what stands where, their BDDL files say.

Every value here is LIBERO's, from libero/libero/envs/problems/libero_living_room_tabletop_manipulation.py,
envs/robots/on_the_ground_panda.py and envs/arenas/living_room_arena.py; tests/libero/test_libero_10.py
compares the compiled scene with LIBERO's own environment. Its suite is LIBERO-10's,
whose tasks span several worlds: `scenes` says which this one stands.
"""

from __future__ import annotations

from dataclasses import replace

from core.worlds import Camera
from core.worlds.libero_10_kitchen_scene3 import KITCHEN

WORLD = replace(
    KITCHEN,
    name="libero_10_living_room",
    scenes=("LIVING_ROOM_SCENE1_", "LIVING_ROOM_SCENE2_", "LIVING_ROOM_SCENE5_", "LIVING_ROOM_SCENE6_"),
    surface_z=0.43676,  # the top of the table's collision boxes (LIBERO's offset says 0.41)
    robot_base=(-0.51, 0.0, 0.42),  # OnTheGroundPanda.base_xpos_offset["living_room_table"](0.7)
    agentview=Camera(
        pos=(0.6065773716836134, 0.0, 0.96),
        quat=(0.6182166934013367, 0.3432307541370392, 0.3432314395904541, 0.6182177066802979),
    ),
    mount=None,
    arena={
        "scene": "scenes/libero_living_room_tabletop_base_style.xml",
        "floor": "seamless_wood_planks_floor.png",  # floor_style="wood-plank"
        "wall": "light-gray-plaster.png",
    },
    table=None,
    table_friction=KITCHEN.table_friction,
)
