"""The dataset's cameras, rendered on the CPU with the fast settings.

MuJoCo's defaults (4x MSAA, shadows, reflections, collision geoms) cost about 4x more per frame
on llvmpipe; none of them helps a policy (README: rendering). Cameras are the scene's profile's
(core/layout.py), and a profile whose frames are stored mirrored gets them mirrored here.
"""

from __future__ import annotations

import atexit

import mujoco
import numpy as np

from oracle.scene import HIDDEN_GROUP, Scene


class Cameras:
    def __init__(self, scene: Scene, size: int, cameras: tuple[str, ...]) -> None:
        known = scene.layout.cameras
        unknown = [c for c in cameras if c not in known]
        if unknown:
            raise ValueError(f"unknown camera(s) {unknown}; known: {', '.join(known)}")
        self.scene = scene
        self.cameras = cameras
        # The offscreen buffer is as large as the frames (the model allows up to MAX_IMAGE_SIZE):
        # every frame clears the whole buffer, and a context allocates it at start.
        scene.model.vis.global_.offwidth = scene.model.vis.global_.offheight = size
        self.renderer = mujoco.Renderer(scene.model, size, size)
        flags = self.renderer.scene.flags
        for flag in (mujoco.mjtRndFlag.mjRND_SHADOW, mujoco.mjtRndFlag.mjRND_REFLECTION, mujoco.mjtRndFlag.mjRND_SKYBOX):
            flags[flag] = False
        self.option = mujoco.MjvOption()
        self.option.geomgroup[0] = False  # collision geoms
        self.option.geomgroup[HIDDEN_GROUP] = False  # parked bodies
        self.option.sitegroup[:] = False
        self._buffers = {c: np.empty((size, size, 3), np.uint8) for c in cameras}
        self._closed = False
        # Free the GL context before interpreter teardown, which otherwise reports EGL errors.
        atexit.register(self.close)

    def render(self) -> dict[str, np.ndarray]:
        """One frame per camera; the arrays are reused by the next call."""
        layout = self.scene.layout
        for cam in self.cameras:
            self.renderer.update_scene(self.scene.data, camera=layout.cameras[cam], scene_option=self.option)
            self.renderer.render(out=self._buffers[cam])
            if layout.mirrored:
                self._buffers[cam][:] = self._buffers[cam][:, ::-1]
        return self._buffers

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self.renderer.close()
