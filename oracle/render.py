"""The dataset's cameras, rendered on the CPU with the fast settings.

MuJoCo's defaults (4x MSAA, shadows, reflections, collision geoms) cost about 4x more per frame
on llvmpipe; none of them helps a policy (docs/GENERATE.md: Performance). A scene of the full look
(core/spec.py) draws reflections, as its world's own simulator does. Cameras are the scene's profile's
(core/profiles.py), and a profile whose frames are stored mirrored gets them mirrored here.
"""

from __future__ import annotations

import atexit
from collections import OrderedDict

import mujoco
import numpy as np

from core.profiles import AGENTVIEW, NATIVE
from core.spec import FULL
from oracle.scene import HIDDEN_GROUP, MIRROR_GROUP, Scene, scene_for

SPARES = scene_for.cache_parameters()["maxsize"]  # released cameras kept per process: as many as scenes


class Cameras:
    def __init__(self, scene: Scene, size: int, cameras: tuple[str, ...]) -> None:
        known = scene.interface.cameras
        unknown = [c for c in cameras if c not in known]
        if unknown:
            raise ValueError(f"unknown camera(s) {unknown}; known: {', '.join(known)}")
        self.scene = scene
        self.size = size
        self.cameras = cameras
        # The offscreen buffer is as large as the frames (the model allows up to MAX_IMAGE_SIZE):
        # every frame clears the whole buffer, and a context allocates it at start.
        scene.model.vis.global_.offwidth = scene.model.vis.global_.offheight = size
        self.renderer = mujoco.Renderer(scene.model, size, size)
        flags = self.renderer.scene.flags
        for flag in (mujoco.mjtRndFlag.mjRND_SHADOW, mujoco.mjtRndFlag.mjRND_SKYBOX):
            flags[flag] = False
        flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = scene.look == FULL
        self.options = {c: self._option(scene.interface.cameras[c]) for c in cameras}
        self._buffers = {c: np.empty((size, size, 3), np.uint8) for c in cameras}
        self._names: np.ndarray | None = None  # labels(): each geom's object, read from the model at the first call
        self._closed = False
        # Free the GL context before interpreter teardown, which otherwise reports EGL errors.
        atexit.register(self.close)

    @staticmethod
    def _option(camera: str) -> mujoco.MjvOption:
        """What a model camera draws: no collision geoms, parked bodies or sites; a mirror plate
        (oracle/scene.py) only from the agentview camera, whose view of the mirror it stands for."""
        option = mujoco.MjvOption()
        option.geomgroup[0] = False  # collision geoms
        option.geomgroup[HIDDEN_GROUP] = False  # parked bodies
        option.geomgroup[MIRROR_GROUP] = camera == NATIVE.cameras[AGENTVIEW]
        option.sitegroup[:] = False
        return option

    def render(self) -> dict[str, np.ndarray]:
        """One frame per camera; the arrays are reused by the next call."""
        interface = self.scene.interface
        for cam in self.cameras:
            self.renderer.update_scene(self.scene.data, camera=interface.cameras[cam], scene_option=self.options[cam])
            self.renderer.render(out=self._buffers[cam])
            if interface.mirrored:
                self._buffers[cam][:] = self._buffers[cam][:, ::-1]
        return self._buffers

    def labels(self) -> dict[str, np.ndarray]:
        """Per camera, the name of the object each pixel of its frame shows (robosuite's object
        name: its top-level body's without `_main`; '' for none), from MuJoCo's segmentation
        render with the frames' options, mirrored as they are: what the picture tests judge each
        object by (eval/sims/libero_env/reference.py writes LIBERO's)."""
        m = self.scene.model
        if self._names is None:  # each geom's object, and '' for no geom
            roots = m.body_rootid[m.geom_bodyid]
            self._names = np.array([m.body(int(r)).name.removesuffix("_main") for r in roots] + [""])
        return {cam: self._names[geoms] for cam, geoms in self.geoms().items()}

    def object_indices(self, camera: str, ids: list[str]) -> np.ndarray:
        """Per pixel of `camera`'s frame, 1 + the index in `ids` of the placed object it shows (0
        for anything else), uint8: the exam's map of its first frame that a predicted point is
        judged by (core/exam.py `frame_objects`)."""
        lookup = np.zeros(self.scene.model.ngeom + 1, np.uint8)  # geom -1 (no geom) reads the last entry
        for k, i in enumerate(ids, start=1):
            lookup[list(self.scene.placed[i].geom_ids)] = k
        return lookup[self.geoms((camera,))[camera]]

    def geoms(self, cameras: tuple[str, ...] | None = None) -> dict[str, np.ndarray]:
        """Per camera, the geom each pixel of its frame shows (-1 for none), mirrored as the frames are."""
        interface, out = self.scene.interface, {}
        self.renderer.enable_segmentation_rendering()
        try:
            for cam in cameras or self.cameras:
                self.renderer.update_scene(self.scene.data, camera=interface.cameras[cam], scene_option=self.options[cam])
                seg = self.renderer.render()  # (objid, objtype) per pixel
                geoms = np.where(seg[..., 1] == mujoco.mjtObj.mjOBJ_GEOM, seg[..., 0], -1)
                out[cam] = geoms[:, ::-1] if interface.mirrored else geoms
        finally:
            self.renderer.disable_segmentation_rendering()
        return out

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self.renderer.close()


_spares: OrderedDict[tuple[Scene, int, tuple[str, ...]], Cameras] = OrderedDict()


def cameras_for(scene: Scene, size: int, cameras: tuple[str, ...]) -> Cameras:
    """Cameras for `scene`: a released set of the same scene, size and cameras where one is kept, else
    new ones. A renderer's start uploads every mesh and texture (about 0.5 s for a LIBERO scene on
    llvmpipe), which a loop making an environment per exam row would otherwise pay per row."""
    kept = _spares.pop((scene, size, cameras), None)
    return kept if kept is not None else Cameras(scene, size, cameras)


def release(cams: Cameras) -> None:
    """Done with `cams`: kept for the next cameras_for of their scene; past SPARES, the oldest kept is closed."""
    if cams._closed:
        return
    key = (cams.scene, cams.size, cams.cameras)
    if key in _spares and _spares[key] is not cams:
        _spares.pop(key).close()
    _spares[key] = cams
    while len(_spares) > SPARES:
        _spares.popitem(last=False)[1].close()
