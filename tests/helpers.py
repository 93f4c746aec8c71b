"""Helpers shared by the tests (importable because pytest puts tests/ on the path)."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import mujoco
import numpy as np

from core.layout import NATIVE
from core.worlds import World
from gen.config import parse
from gen.run import generate
from oracle.scene import Scene

ROOT = Path(__file__).resolve().parent.parent
LIBERO_PYTHON = ROOT / ".venv-libero" / "bin" / "python"
# LIBERO's initial states per task the picture tests compare (each a render in LIBERO's env and in
# ours): 2 in `make test`; the README's figures, over the first 5, with LIBERO_PICTURE_STATES=5.
PICTURE_STATES = int(os.environ.get("LIBERO_PICTURE_STATES", "2"))


def liberos_own(command: str, request: dict, out: Path) -> Path:
    """Run a command of scripts/libero_reference.py in LIBERO's own environment (`.venv-libero`)."""
    assert LIBERO_PYTHON.is_file(), f"{LIBERO_PYTHON} is missing: `make setup` builds LIBERO's reference environment"
    request_file = out.with_name(out.name + ".request.json")
    request_file.write_text(json.dumps(request))
    done = subprocess.run(
        [str(LIBERO_PYTHON), str(ROOT / "scripts" / "libero_reference.py"), command, str(request_file), str(out)],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return out


def canonical_reports(out: Path, trials: dict[str, int], world: str = "libero_object") -> dict[str, dict]:
    """A canonical exam of `world` on the first initial state of each task (gen.canonical), each
    policy taken on its first `trials[policy]` trials: the policies' reports."""
    from core.exam import read
    from eval.battery import take
    from eval.registry import make
    from gen.canonical import CanonicalOptions, build

    build(CanonicalOptions(world=world, states=1, image_size=32, out=str(out / "canonical")))
    exam = read(out / "canonical")
    reports = {}
    for policy, n in trials.items():
        rows = exam.trials[exam.trials["trial"] < n]
        reports[policy], _ = take(exam, rows, make(policy), out / policy, workers=2, policy_name=policy, baseline=False)
    return reports


def liberos_replay(dataset: Path, world: World) -> dict:
    """A dataset's episodes as scripts/libero_reference.py's `replay` takes them, rebuilt from
    their records alone: LIBERO's instance names (a place on furniture: its site's), poses, robot
    joints and recorded actions; `target` is what moves and `container` where it goes. A world
    with fixtures replays in its suite's own scene, the fixtures where the records stand them."""
    from core.layout import ACTION_KEY
    from gen import scenes
    from gen.lerobot_reader import LeRobotReader

    reader, sites = LeRobotReader(dataset), {k.name: k.params["site"] for k in world.kinds.values() if k.model == "site"}
    episodes = []
    for record in scenes.read(dataset).itertuples():
        scene, params = json.loads(record.scene), json.loads(record.spec)["task"]["params"]
        instance = {o["id"]: sites.get(o["kind"], o["instance"]) for o in scene["objects"]}
        moved, goal = (params["object"], record.target) if "object" in params else (record.target, params["destination"])
        rows = reader.data[reader.data.episode_index == record.episode_index]
        episodes.append(
            {
                "objects": [
                    {k: o[k] for k in ("instance", "kind", "pos", "quat")} for o in scene["objects"] if o["kind"] not in sites
                ],
                "target": instance[moved],
                "container": instance[goal],
                "arm": scene["robot"]["arm"],
                "fingers": scene["robot"]["fingers"],
                "actions": np.stack(rows[ACTION_KEY].to_numpy()).astype(float).tolist(),
            }
        )
    if not world.fixtures:
        return {"episodes": episodes}
    fixtures = {
        tuple([f["instance"], *f["pos"], *f["quat"]]) for r in scenes.read(dataset).scene for f in json.loads(r)["fixtures"]
    }
    assert len(fixtures) == len(world.fixtures), "every record names every fixture, at one pose"
    return {"suite": world.suite, "fixtures": [list(f) for f in sorted(fixtures)], "episodes": episodes}


def make_dataset(out: Path, *overrides: str) -> Path:
    """Generate a dataset through the real CLI config and pipeline."""
    generate(parse([f"out={out}", *overrides]), progress=False)
    return out


def body_image(scene: Scene, camera: str, size: int = 128) -> np.ndarray:
    """The body id seen at each pixel of an upright render of `camera` (-1: none; collision geoms hidden)."""
    renderer = mujoco.Renderer(scene.model, size, size)
    renderer.enable_segmentation_rendering()
    option = mujoco.MjvOption()
    option.geomgroup[0] = False
    renderer.update_scene(scene.data, camera=NATIVE.cameras[camera], scene_option=option)
    seg = renderer.render()
    renderer.close()
    is_geom = seg[..., 1] == mujoco.mjtObj.mjOBJ_GEOM
    return np.where(is_geom, scene.model.geom_bodyid[np.where(is_geom, seg[..., 0], 0)], -1)


def visible_bodies(scene: Scene, camera: str, size: int = 128) -> dict[int, int]:
    """Pixels per body id in a segmentation render of `camera`."""
    image = body_image(scene, camera, size)
    bodies, counts = np.unique(image[image >= 0], return_counts=True)
    return dict(zip(bodies.tolist(), counts.tolist()))
