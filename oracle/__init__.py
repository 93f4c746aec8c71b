"""The scripted oracle: scene builder, IK, trajectories, skills, success checks, cameras."""

import os

# Headless CPU rendering unless the user chose otherwise. MuJoCo reads MUJOCO_GL at import, so
# this must run before the first `import mujoco` (gen/ and eval/ import this package first).
os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("PYOPENGL_PLATFORM", os.environ["MUJOCO_GL"])
os.environ.setdefault("LP_NUM_THREADS", "1")  # llvmpipe threads per renderer: workers scale by process
