"""LIBERO-Spatial's world: LIBERO's tabletop arena (its `Libero_Tabletop_Manipulation` problem: a
1.0 x 1.2 m table with its top at 0.9 m), the Panda on its Rethink mount at the table's edge
(`MountedPanda`), LIBERO's agentview camera and the robot's eye-in-hand camera, the wooden
cabinet and the flat stove where every LIBERO-Spatial task stands them, and LIBERO's black bowls,
plate, ramekin and cookie box (core/libero.py).

Every value here is LIBERO's, from libero/libero/envs/problems/libero_tabletop_manipulation.py,
envs/robots/mounted_panda.py, envs/bddl_base_domain.py and the suite's BDDL files (the fixtures
at the centres of their regions, the cabinet turned by the middle of its yaw range: LIBERO draws
both anew within them at every reset, within 1 cm and 2 degrees); tests/libero/test_libero_world.py
compares the compiled scene, its pictures and its physics with LIBERO's own environment.
"""

from __future__ import annotations

from core import libero
from core.worlds import Camera, Placed, World
from core.worlds.libero_object import ROBOT_HOME

SUITE = "libero_spatial"
TABLE_TOP = 0.9
FIXTURE_Z = TABLE_TOP + 0.005  # where LIBERO's placement puts a fixture's body on the table

WORLD = World(
    name=SUITE,
    kinds=libero.KINDS,
    surface_z=TABLE_TOP,
    reach=(-0.3, 0.25, -0.35, 0.35),
    robot_base=(-0.66, 0.0, 0.0),  # MountedPanda.base_xpos_offset["table"](1.0); the mount lifts it
    robot_home=ROBOT_HOME,  # MountedPanda.init_qpos, OnTheGroundPanda's too
    finger_home=libero.FINGER_HOME,
    finger_target=libero.FINGER_TARGET,
    profiles=("libero",),
    agentview=Camera(
        pos=(0.6586131746834771, 0.0, 1.6103500240372423),
        quat=(0.6380177736282349, 0.3048497438430786, 0.30484986305236816, 0.6380177736282349),
    ),
    park=tuple((x, y) for x in (-1.5, -1.2) for y in (-0.9, -0.6, -0.3, 0.0, 0.3, 0.6)),
    park_z=-1.0,  # under the floor: out of view and out of contact
    builder="libero",
    robot_faces=600,
    mount="RethinkMount",
    integrator="Euler",
    arena={
        "scene": "scenes/libero_tabletop_base_style.xml",
        "floor": "light-gray-floor-tile.png",
        "wall": "light-gray-plaster.png",
    },
    table=((1.0, 1.2, 0.05), (0.0, 0.0, TABLE_TOP)),
    fixtures=(
        Placed(libero.FIXTURES["wooden_cabinet"], "wooden_cabinet_1", (0.03, -0.27, FIXTURE_Z), 2.6927937),
        Placed(libero.FIXTURES["flat_stove"], "flat_stove_1", (-0.41, -0.14, FIXTURE_Z)),
    ),
    suite=SUITE,
    episode_steps=280,  # lerobot's envs/libero.py: libero_spatial's max_episode_steps
    body_name=libero.instance,
    requires=libero.require,
)
