"""`python -m gen.canonical world=libero_object` (or libero_spatial, libero_goal): an exam on LIBERO's own initial states.

Its task rows are exactly a LIBERO suite's tasks: LIBERO's initial states (every one of the 50
per task, or `states=` of them drawn with `seed=`), LIBERO's instructions, the rollout horizon
and settle steps lerobot's LIBERO environment uses. On each state the swap rows are the world's
referent type's (its `canonical` design of the task: in LIBERO-Object every other grocery, in
LIBERO-Spatial the other bowl, named by where it stands), and occ and nonsense rows follow, as
in every exam (core/exam.py). A LIBERO-trained policy's task rate here is its published LIBERO
number; its swap rate is whether it reads the instruction. The `position` policy is the
shortcut LIBERO's layouts reward: it knows the scene and fetches what that task's target was.

The states are LIBERO's exactly (joints set by name from LIBERO's state vectors), so the first
settle steps show what they show in LIBERO: objects placed slightly into the floor pop up and
settle.
"""

from __future__ import annotations

import sys
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

import referents
from core import exam, worlds
from core.layout import STATE_KEY, TASK_KEY, layout
from core.spec import EpisodeSpec, SceneObject, SimSettings, yaw_of
from core.worlds import libero
from gen.audit import audit
from gen.cli import UserError, main
from gen.config import check_output, check_seed
from gen.partial import staging
from referents import Referent

if TYPE_CHECKING:
    from oracle.scene import Scene


@dataclass
class CanonicalOptions:
    world: str = "libero_object"  # a LIBERO world (core/worlds/): its suite's tasks and initial states
    states: int = 50  # initial states per task (LIBERO has 50); fewer are drawn with `seed`
    seed: int = 0
    image_size: int = 256  # the cameras' frames, pixels (the exam's policy side)
    out: str | None = None  # default datasets/<world>-canonical
    overwrite: bool = False


def _options(options: CanonicalOptions) -> tuple[worlds.World, Referent, Path]:
    try:
        world = worlds.world(options.world)
    except worlds.UnknownWorld as exc:
        raise UserError(str(exc)) from None
    if not world.suite:
        raise UserError(f"world {world.name} has no LIBERO suite; canonical exams are LIBERO's: {_libero_worlds()}")
    try:
        world.requires()
    except worlds.WorldUnavailable as exc:
        raise UserError(f"world={world.name}: {exc}") from None
    check_seed(options.seed)
    if not 1 <= options.states <= 50:
        raise UserError(f"states must be between 1 and 50 (LIBERO's initial states per task), got {options.states}")
    if not 16 <= options.image_size <= worlds.MAX_IMAGE_SIZE or options.image_size % 2:
        raise UserError(f"image_size must be an even number of pixels in [16, {worlds.MAX_IMAGE_SIZE}], got {options.image_size}")
    out = Path(options.out or f"datasets/{world.name}-canonical")
    check_output(out, options.overwrite)
    types = [r for r in referents.of_world(world.name) if referents.load(r).code.canonical is not None]
    if not types:
        raise UserError(
            f"world {world.name} has no referent type that lays out LIBERO's tasks yet; canonical exams: {_canonical_worlds()}"
        )
    return world, referents.load(types[0]), out


def _libero_worlds() -> str:
    return ", ".join(name for name in worlds.names() if worlds.world(name).suite)


def _canonical_worlds() -> str:
    return ", ".join(name for name in worlds.names() if any(referents.load(r).code.canonical for r in referents.of_world(name)))


def trial_spec(referent: Referent, world: worlds.World, task: str, index: int, seed: int, sim: SimSettings) -> EpisodeSpec:
    """A LIBERO task's scene as an episode spec (the referent type's `canonical` design of it):
    its objects under the design's ids, each where the task's region puts it until the initial
    state poses it, LIBERO's instruction, the swaps."""
    problem = libero.problem(world.suite, task)
    assert referent.code.canonical is not None
    design = referent.code.canonical(referent.config, problem)
    if design is None:
        raise ValueError(f"{task} is not one of referent {referent.name}'s tasks")
    objects = []
    for p in design.placements:
        kind = world.kind(p.candidate.kind)
        x, y, *_ = referent.config.layout.slots[p.slot]
        z = kind.rest_z(referent.config.layout.surface(p.slot, world.surface_z))
        objects.append(
            SceneObject(p.id, p.candidate.kind, p.candidate.name, p.slot, (x, y, z), attributes=dict(p.candidate.attributes))
        )
    return EpisodeSpec(
        referent=referent.name,
        index=index,
        seed=seed,
        objects=tuple(objects),
        target=design.target,
        instruction=design.instruction,
        template=design.template,
        counterfactuals=design.counterfactuals,
        assets=referent.assets(),
        task=design.task or referent.config.task,
        sim=sim,
        split="exam",
    )


def covered(referent: Referent, world: worlds.World) -> list[str]:
    """The suite's tasks the referent type can lay out (LIBERO-Goal's drawers and knob are not)."""
    canonical = referent.code.canonical
    assert canonical is not None
    return [t for t in libero.tasks(world.suite) if canonical(referent.config, libero.problem(world.suite, t)) is not None]


def build(options: CanonicalOptions) -> None:
    world, referent, out = _options(options)
    from tqdm import tqdm

    from oracle.scene import scene_for

    started = time.perf_counter()
    profile = layout(world.profiles[0])
    sim = SimSettings(options.image_size, 20, profile.camera_names, world.robot_home, profile.name, world.name)
    tasks = covered(referent, world)
    rng = np.random.default_rng(options.seed)
    chosen = {task: sorted(rng.choice(50, options.states, replace=False).tolist()) for task in tasks}
    scene = scene_for(referent.assets(), profile.name, world.name)
    rows, specs = [], []
    bar = tqdm(total=sum(map(len, chosen.values())), desc=f"{world.suite} initial states", unit="state")
    for task in tasks:
        for s in chosen[task]:
            spec = load_state(scene, referent, world, task, s, sim, len(specs), options.seed)
            values = {a.id: a.value for a in referent.alternatives(spec)}
            ee = [float(v) for v in scene.ee_pos()]
            state = scene.physics_state().astype(np.float64).tolist()
            rows += exam.trial_rows(len(specs), spec, values, state, world.episode_steps, ee, scene.settled(spec))
            specs.append(spec)
            bar.update()
    bar.close()
    report = audit(referent, specs)
    with staging(out) as root:
        root.mkdir(parents=True)
        exam.write(root, rows, _header(options, world, referent, profile.name, sim, chosen, report))
    print(
        f"wrote an exam of {len(specs)} LIBERO initial states ({len(tasks)} tasks x {options.states}) to {out} "
        f"in {time.perf_counter() - started:.1f} s\ntake it with: python -m eval policy=<policy> exam={out}"
    )


def load_state(
    scene: Scene, referent: Referent, world: worlds.World, task: str, state: int, sim: SimSettings, index: int = 0, seed: int = 0
) -> EpisodeSpec:
    """Put `scene` in a LIBERO task's initial state number `state` (joints set by name from
    LIBERO's state vector); returns the trial's spec, its objects posed as that state poses them."""
    problem = libero.problem(world.suite, task)
    vector = libero.initial_states(world.suite, task)[state]
    spec = _posed(trial_spec(referent, world, task, index, seed, sim), vector, problem, world)
    scene.reset(spec)
    scene.set_joints(*libero.split_state(vector, problem))
    return spec


def _posed(spec: EpisodeSpec, state: np.ndarray, problem: libero.Problem, world: worlds.World) -> EpisodeSpec:
    """The spec with each object where the LIBERO state puts it (position, and turn about z)."""
    qpos, _ = libero.split_state(state, problem)
    objects = []
    for obj, instance in zip(spec.objects, problem.objects):
        pose = qpos[f"{instance}_joint0"]
        at = tuple(round(float(v), 5) for v in pose[:3])
        objects.append(replace(obj, pos=at, yaw=round(yaw_of(pose[3:], world.kind(obj.kind).quat), 5)))
    return replace(spec, objects=(*objects, *spec.objects[len(objects) :]))  # places on furniture stay


def _header(
    options: CanonicalOptions, world: worlds.World, referent: Referent, profile: str, sim: SimSettings, chosen: dict, report: dict
) -> dict:
    features = layout(profile)
    return {
        "referent": referent.name,
        "seed": options.seed,
        "split": "exam",
        "command": f"python -m gen.canonical world={world.name} states={options.states} seed={options.seed} "
        f"image_size={options.image_size}",
        "profile": profile,
        "world": world.name,
        "canonical": {
            "suite": world.suite,
            "states": {task: states for task, states in chosen.items()},
            "episode_steps": world.episode_steps,
            "settle_steps": features.settle_steps,
        },
        "observation": {
            "keys": [features.image_key(c) for c in sim.cameras] + [STATE_KEY],
            "instruction": f"the `instruction` column of trials.parquet; info['instruction'] in the gymnasium env; "
            f"`{TASK_KEY}` in python -m eval's observation dicts",
            "image_size": sim.image_size,
            "fps": sim.fps,
            "state_names": list(features.state_names),
            "action_names": list(features.action_names),
            "action": features.action_meaning,
            "mirrored": features.mirrored,
            "settle_steps": features.settle_steps,
        },
        "referent_spec": asdict(referent.config),
        "audit": report,
    }


if __name__ == "__main__":
    sys.exit(main("python -m gen.canonical", CanonicalOptions, build, doc=__doc__))
