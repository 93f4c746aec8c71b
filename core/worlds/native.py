"""The native world: robosuite's Panda on its mount behind robosuite's table, this project's
camera, robosuite's objects (core/catalog.py).

Plain constants, importable without a simulator, so that referents can lay out scenes (and the
exam can document them) without building a model.
"""

from __future__ import annotations

from core import catalog
from core.worlds import Camera, World

TABLE_SIZE = (0.8, 0.8, 0.05)  # robosuite TableArena full size (x, y, thickness), metres
TABLE_TOP_Z = 0.8  # height of the table surface
ROBOT_BASE = (-0.56, 0.0, 0.0)  # Panda on robosuite's RethinkMount, behind the table edge
# The robot's joint-space home pose (robosuite's Panda init_qpos): every episode starts here.
PANDA_HOME: tuple[float, ...] = (0.0, 0.19634954, 0.0, -2.61799388, 0.0, 2.94159265, 0.78539816)
FINGER_OPEN = 0.04  # finger joint travel, metres

# Camera poses: agentview looks at the whole workspace from the front, so every slot and the
# gripper stay in frame; wrist is robosuite's eye-in-hand camera.
AGENTVIEW_POS = (0.55, 0.0, 1.55)
AGENTVIEW_LOOKAT = (-0.09, 0.0, 0.86)
AGENTVIEW_FOVY = 50.0

# Objects not in an episode rest on the floor under the table top, hidden from every camera.
PARK_X = (-0.24, -0.08, 0.08, 0.24)
PARK_Y = (-0.3, -0.1, 0.1, 0.3)
MARGIN = 0.05  # objects stand at least this far inside the table's edges

WORLD = World(
    name="native",
    kinds=catalog.KINDS,
    surface_z=TABLE_TOP_Z,
    reach=(
        -TABLE_SIZE[0] / 2 + MARGIN,
        TABLE_SIZE[0] / 2 - MARGIN,
        -TABLE_SIZE[1] / 2 + MARGIN,
        TABLE_SIZE[1] / 2 - MARGIN,
    ),
    robot_base=ROBOT_BASE,
    robot_home=PANDA_HOME,
    finger_home=FINGER_OPEN,
    finger_target=FINGER_OPEN,
    profiles=("native", "libero"),
    agentview=Camera(AGENTVIEW_POS, lookat=AGENTVIEW_LOOKAT, fovy=AGENTVIEW_FOVY),
    park=tuple((x, y) for x in PARK_X for y in PARK_Y),
    park_z=0.0,
    builder="table",
)
