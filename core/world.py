"""The fixed world every scene shares: table, robot base and camera poses.

Plain constants, importable without a simulator, so that referents can lay out scenes (and the
exam can document them) without building a model.
"""

from __future__ import annotations

TABLE_SIZE = (0.8, 0.8, 0.05)  # robosuite TableArena full size (x, y, thickness), metres
TABLE_TOP_Z = 0.8  # height of the table surface
ROBOT_BASE = (-0.56, 0.0, 0.0)  # Panda on robosuite's RethinkMount, behind the table edge

# Camera poses: agentview looks at the whole workspace from the front, so every slot and the
# gripper stay in frame; wrist is robosuite's eye-in-hand camera.
AGENTVIEW_POS = (0.55, 0.0, 1.55)
AGENTVIEW_LOOKAT = (-0.09, 0.0, 0.86)
AGENTVIEW_FOVY = 50.0

# Objects not in an episode rest on the floor under the table top, hidden from every camera.
PARK_X = (-0.24, -0.08, 0.08, 0.24)
PARK_Y = (-0.3, -0.1, 0.1, 0.3)

PHYSICS_DT = 0.002  # simulation timestep, seconds; control periods are whole multiples of it
MAX_IMAGE_SIZE = 1024  # largest square frame a renderer may ask for
