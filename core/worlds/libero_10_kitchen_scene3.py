"""LIBERO-10's KITCHEN_SCENE3 (turn on the stove and put the moka pot on it): LIBERO's kitchen
(its `Libero_Kitchen_Tabletop_Manipulation` problem: LIBERO-Spatial's table, mounted Panda and
cameras in the kitchen's scene file, floor and walls, the table's friction left at robosuite's 1),
the flat stove where the scene's region stands it, the moka pot and the frying pan.

Every value here is LIBERO's, from libero/libero/envs/problems/libero_kitchen_tabletop_manipulation.py,
envs/arenas/kitchen_arena.py and the task's BDDL file; tests/libero/test_libero_10.py compares the
compiled scene with LIBERO's own environment. Its suite is LIBERO-10's,
whose tasks span several worlds: `scenes` says which this one stands.
"""

from __future__ import annotations

from dataclasses import replace

from core import libero
from core.worlds import Placed, libero_spatial

KITCHEN = replace(
    libero_spatial.WORLD,
    name="libero_10_kitchen",
    arena={
        "scene": "scenes/libero_kitchen_tabletop_base_style.xml",
        "floor": "gray_ceramic_tile.png",  # floor_style="gray-ceramic"
        "wall": "yellow_linen_wall_texture.png",  # wall_style="yellow-linen"
        # the flat stove's mirror top shows the kitchen's dark units behind the robot, not the tabletop's
        # light wall (oracle/scene.py MIRROR_LOOK): fitted to LIBERO's frames, as that was
        "mirror_rgba": "0.33 0.32 0.3 1",
        "mirror_emission": "0.1",
    },
    table_friction=(1.0, 0.005, 0.0001),  # KitchenTableArena's default, which LIBERO's kitchen problem keeps
    robot_faces=2000,
    fixtures=(),
    suite="libero_10",
    episode_steps=520,  # lerobot's envs/libero.py: libero_10's max_episode_steps (its longest demonstration: 505)
)

WORLD = replace(
    KITCHEN,
    name="libero_10_kitchen_scene3",
    scenes=("KITCHEN_SCENE3_",),
    fixtures=(Placed(libero.FIXTURES["flat_stove"], "flat_stove_1", (-0.2, 0.2, libero_spatial.FIXTURE_Z)),),
)
