"""LIBERO-Object's world: LIBERO's floor arena (its `Libero_Floor_Manipulation` problem), the
Panda standing on the floor without a mount (`OnTheGroundPanda`), LIBERO's agentview camera
and the robot's eye-in-hand camera, LIBERO's groceries and basket (core/libero.py).

Every value here is LIBERO's, from libero/libero/envs/problems/libero_floor_manipulation.py,
envs/robots/on_the_ground_panda.py, envs/arenas/empty_arena.py and bddl_base_domain.py;
tests/libero/test_libero_world.py compares the compiled scene, its pictures and its physics with
LIBERO's own environment.
"""

from __future__ import annotations

import numpy as np

from core import libero
from core.worlds import Camera, World

SUITE = "libero_object"
# OnTheGroundPanda.init_qpos; LIBERO's initial states add N(0, 0.02) noise to it.
ROBOT_HOME = (0.0, -0.161037389, 0.0, -2.44459747, 0.0, 2.2267522, float(np.pi / 4))

WORLD = World(
    name=SUITE,
    kinds=libero.KINDS,
    surface_z=0.0,
    reach=(-0.3, 0.3, -0.35, 0.35),
    robot_base=(-0.6, 0.0, 0.0),  # OnTheGroundPanda.base_xpos_offset["empty"]
    robot_home=ROBOT_HOME,
    finger_home=libero.FINGER_HOME,
    finger_target=libero.FINGER_TARGET,
    profiles=("libero",),
    agentview=Camera(
        pos=(0.8965773716836134, 5.216182733499864e-07, 0.65),
        quat=(0.6182166934013367, 0.3432307541370392, 0.3432314395904541, 0.6182177066802979),
    ),
    park=tuple((x, y) for x in (-1.5, -1.2, -0.9) for y in (-0.9, -0.6, -0.3, 0.0, 0.3, 0.6)),
    park_z=-1.0,  # under the floor: out of view and out of contact
    builder="libero",
    # The Panda's visual meshes at 600 triangles each instead of 2,000: a fifth less time per frame,
    # and LIBERO's own frames still within 2.9/255 (agentview) and 3.2/255 (wrist) (docs/LIBERO.md).
    robot_faces=600,
    mount=None,
    integrator="Euler",  # robosuite's default, which LIBERO keeps
    arena={
        "scene": "scenes/libero_floor_base_style.xml",
        "floor": "light-gray-floor-tile.png",  # EmptyArena(floor_style="light-gray")
        "wall": "light-gray-plaster.png",  # wall_style="light-gray-plaster"
    },
    suite=SUITE,
    episode_steps=280,  # lerobot's envs/libero.py: libero_object's max_episode_steps
    body_name=libero.instance,
    requires=libero.require,
)
