"""The episode spec: the one currency of the project.

Referents produce specs, the oracle consumes them, the writer records them and the exam and
battery replay them. A spec is plain, immutable data that round-trips through JSON, carries a
version, and hashes the same wherever it is computed, so that a scene can be rebuilt and
recognised from the spec alone.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field, replace
from typing import Any

from core import profiles, worlds
from core.profiles import NATIVE, Profile
from core.rotations import yaw_quat
from core.worlds.native import PANDA_HOME

SPEC_VERSION = 1


class SpecError(ValueError):
    """A spec (or its JSON) is malformed or of an unsupported version."""


@dataclass(frozen=True)
class SceneObject:
    """One object on the table.

    `id` is unique within the scene, `kind` is the catalog entry that builds it, `name` is the
    noun instructions use for it, and `pos` is the world position of its body origin while it
    rests on the table.
    """

    id: str
    kind: str
    name: str
    slot: int
    pos: tuple[float, float, float]
    yaw: float = 0.0
    attributes: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Counterfactual:
    """The instruction with one word (or phrase) changed, and what it then asks for.

    `target` is the object the changed instruction names; `program` is set when the change
    names another motor program (e.g. "lift" -> "push") and is None when it keeps the episode's.
    `goal` is which of a task of more goals (LIBERO-10's) the changed words name: 0 the first (the
    episode's target), k the k-th that `task.params["then"]` lists; the others stay as asked.
    """

    instruction: str
    target: str
    changed: tuple[str, str]
    program: str | None = None
    goal: int = 0

    def to_dict(self) -> dict[str, Any]:
        """As specs and scene records write it: `goal` only where not the first (which is all there
        was before it, so their bytes are unchanged)."""
        d = asdict(self)
        if not self.goal:
            del d["goal"]
        return d


THEN = "then"  # a task's goals after its first, in its params: [{"program", "target", "params"}, ...] (EpisodeSpec.goals)


@dataclass(frozen=True)
class TaskSpec:
    """What the oracle must do and how success is judged (see core/programs.py)."""

    program: str = "pick"
    lift_margin: float = 0.05
    params: dict[str, Any] = field(default_factory=dict)


# How the cameras draw a scene (oracle/scene.py, oracle/render.py). `fast`: meshes lightened and
# no reflections, a mirror top stood in for by a plate (docs/LIBERO.md: each object as LIBERO draws it). `full`: every mesh as
# its file has it and MuJoCo's reflections, as the world's own simulator draws it (LIBERO's
# scanned basket and bowls, its mirror stove top), at 2.7-3.9x the generation time (docs/LIBERO.md: look=full).
FAST, FULL = "fast", "full"
LOOKS = (FAST, FULL)


@dataclass(frozen=True)
class Setup:
    """Everything besides the objects that determines the simulation and its recording: the world,
    the robot's home, the profile recorded, cameras, frame size and rate, the look."""

    image_size: int = 128
    fps: int = 20
    cameras: tuple[str, ...] = NATIVE.camera_names
    robot_home: tuple[float, ...] = PANDA_HOME
    profile: str = NATIVE.name  # its features: cameras, state, action and controller (core/profiles.py)
    world: str = "native"  # where the episode happens: arena, robot, cameras, object models (core/worlds/)
    look: str = FAST  # how the cameras draw it (LOOKS)

    def __post_init__(self) -> None:
        profiles.named(self.profile)  # an unknown profile fails here, naming the known ones
        if self.look not in LOOKS:
            raise ValueError(f"unknown look {self.look!r}; known: {', '.join(LOOKS)}")

    @property
    def interface(self) -> Profile:
        """What is recorded: the profile's cameras, state, action and controller."""
        return profiles.named(self.profile)


@dataclass(frozen=True)
class EpisodeSpec:
    """A complete, replayable description of one episode.

    `assets` is the model's inventory (catalog kind -> number of bodies): objects not in the
    scene are parked out of view, so every episode of a dataset shares one compiled model.
    `attempt` counts oracle failures: a failed demo is re-realised with new pose noise but the
    same roles, so resampling never changes the role balance. `split` ("train" or "exam")
    selects the random stream, so exam scenes never coincide with training scenes.
    """

    referent: str
    index: int
    seed: int
    objects: tuple[SceneObject, ...]
    target: str
    instruction: str
    template: str
    counterfactuals: tuple[Counterfactual, ...]
    assets: tuple[tuple[str, int], ...]
    task: TaskSpec = TaskSpec()
    setup: Setup = Setup()  # serialized under its first name, "sim" (the spec's JSON and hash are unchanged)
    attempt: int = 0
    split: str = "train"
    version: int = SPEC_VERSION
    # A training episode whose instruction changes mid-course (`switched=`): the counterfactual it
    # becomes where the hand has come near what it first takes hold of (oracle/episode.py); None
    # for the rest, whose JSON and hash stay what they always were.
    switch: int | None = None

    def choice(self, cf: Counterfactual | None = None) -> tuple[str, str]:
        """(object, program) the instruction, or a counterfactual of it, asks for."""
        if cf is None:
            return self.target, self.task.program
        return cf.target, cf.program or self.task.program

    def asking(self, target: str, program: str, goal: int = 0) -> EpisodeSpec:
        """The episode with its goal number `goal` (0 the first) asking `program` of `target`
        instead, its other goals as they are: what a counterfactual of it asks in all."""
        if goal == 0:
            return replace(self, target=target, task=replace(self.task, program=program))
        then = [dict(g) for g in self.task.params[THEN]]
        then[goal - 1].update(target=target, program=program)
        return replace(self, task=replace(self.task, params={**self.task.params, THEN: then}))

    def goals(self) -> tuple[EpisodeSpec, ...]:
        """The task's goals in the order the oracle reaches them, each as a spec of one goal: itself,
        or for a task of more (LIBERO-10's "put both ...", "... and close it") the first, then each
        that `task.params["then"]` lists (its `program`, `target` and `params`), in the same scene."""
        then = self.task.params.get(THEN)
        if not then:
            return (self,)
        first = replace(self, task=replace(self.task, params={k: v for k, v in self.task.params.items() if k != THEN}))
        return first, *(
            replace(self, target=g["target"], task=replace(self.task, program=g["program"], params=dict(g.get("params", {}))))
            for g in then
        )

    def after_switch(self) -> EpisodeSpec:
        """The episode as asked once its instruction has changed (itself when it never does): the
        counterfactual's words, target and program, in the same scene."""
        if self.switch is None:
            return self
        cf = self.counterfactuals[self.switch]
        return replace(self.asking(*self.choice(cf), cf.goal), instruction=cf.instruction, switch=None)

    def object(self, object_id: str) -> SceneObject:
        for obj in self.objects:
            if obj.id == object_id:
                return obj
        raise KeyError(f"no object {object_id!r} in episode {self.index}")

    def public(self) -> EpisodeSpec:
        """The scene alone, as a policy may see it: objects, poses, inventory and setup,
        with the answer (target, instruction, counterfactuals, task) withheld."""
        return replace(
            self, target="", instruction="", template="", counterfactuals=(), task=TaskSpec(program="", params={}), switch=None
        )

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["sim"] = d.pop("setup")
        if self.setup.profile == NATIVE.name:  # specs of the native profile keep the JSON (and hash) they always had
            del d["sim"]["profile"]
        if self.setup.world == "native":  # and so do those of the native world
            del d["sim"]["world"]
        if self.setup.look == FAST:  # and those drawn with the fast look, which is all there was before `look`
            del d["sim"]["look"]
        if self.switch is None:  # and those whose instruction never changes
            del d["switch"]
        d["counterfactuals"] = [c.to_dict() for c in self.counterfactuals]
        return d

    def to_json(self) -> str:
        """Canonical JSON: sorted keys, no whitespace, so equal specs give equal strings."""
        return json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))

    @property
    def hash(self) -> str:
        return hashlib.sha256(self.to_json().encode()).hexdigest()[:16]

    @property
    def scene_hash(self) -> str:
        """Identity of the physical scene (objects and poses), whatever the instruction says.

        Poses are rounded to a millimetre so that a scene is recognised across splits.
        """
        scene = [
            (o.kind, o.slot, [round(v, 3) for v in o.pos], round(o.yaw, 3), sorted(o.attributes.items()))
            for o in sorted(self.objects, key=lambda o: o.id)
        ]
        return hashlib.sha256(json.dumps(scene, sort_keys=True).encode()).hexdigest()[:16]

    def scene_record(self) -> dict[str, Any]:
        """The `scene` column of meta/scenes.parquet. Outside the native world every object also
        carries the world's own name for it (`instance`, e.g. LIBERO's `alphabet_soup_1`) and
        its orientation (`quat`, w x y z), and the record names the world, its furniture
        (`fixtures`: each one's world name, e.g. LIBERO's `flat_stove_1`, kind, body position and
        orientation) and the robot's starting joints (`robot`: arm and finger joint positions, in
        the model's joint order), so the episode can be rebuilt in the world's own simulator."""
        objects = [{**asdict(o), "pos": list(o.pos)} for o in self.objects]
        if self.setup.world == "native":
            return {"objects": objects}
        world, seen = worlds.world(self.setup.world), {}
        for record, obj in zip(objects, self.objects):
            seen[obj.kind] = seen.get(obj.kind, -1) + 1
            record["instance"] = world.body_name(obj.kind, seen[obj.kind])
            record["quat"] = list(yaw_quat(obj.yaw, world.kind(obj.kind).quat))
        fingers = world.finger_home
        fixtures = [
            {"instance": f.name, "kind": f.fixture.kind, "pos": list(f.pos), "quat": list(yaw_quat(f.yaw))}
            for f in world.fixtures
        ]
        return {
            "world": world.name,
            "objects": objects,
            "fixtures": fixtures,
            "robot": {"arm": list(self.setup.robot_home), "fingers": [fingers, -fingers]},
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> EpisodeSpec:
        try:
            version = d["version"]
            if version != SPEC_VERSION:
                raise SpecError(f"episode spec version {version} is not supported (expected {SPEC_VERSION})")
            switch = d.get("switch")
            if switch is not None and not 0 <= int(switch) < len(d["counterfactuals"]):
                raise SpecError(f"episode spec's switch {switch} names no counterfactual (it has {len(d['counterfactuals'])})")
            goals = 1 + len(d["task"].get("params", {}).get(THEN) or ())
            if any(not 0 <= int(c.get("goal", 0)) < goals for c in d["counterfactuals"]):
                raise SpecError(f"an episode spec's counterfactual names a goal its task does not have (it has {goals})")
            return cls(
                referent=str(d["referent"]),
                index=int(d["index"]),
                seed=int(d["seed"]),
                objects=tuple(
                    SceneObject(
                        id=o["id"],
                        kind=o["kind"],
                        name=o["name"],
                        slot=int(o["slot"]),
                        pos=tuple(float(v) for v in o["pos"]),
                        yaw=float(o["yaw"]),
                        attributes=dict(o.get("attributes", {})),
                    )
                    for o in d["objects"]
                ),
                target=str(d["target"]),
                instruction=str(d["instruction"]),
                template=str(d["template"]),
                counterfactuals=tuple(
                    Counterfactual(c["instruction"], c["target"], tuple(c["changed"]), c.get("program"), int(c.get("goal", 0)))
                    for c in d["counterfactuals"]
                ),
                assets=tuple((str(k), int(n)) for k, n in d["assets"]),
                task=TaskSpec(**d["task"]),
                setup=Setup(
                    image_size=int(d["sim"]["image_size"]),
                    fps=int(d["sim"]["fps"]),
                    cameras=tuple(d["sim"]["cameras"]),
                    robot_home=tuple(float(v) for v in d["sim"]["robot_home"]),
                    profile=str(d["sim"].get("profile", NATIVE.name)),
                    world=str(d["sim"].get("world", "native")),
                    look=str(d["sim"].get("look", FAST)),
                ),
                attempt=int(d["attempt"]),
                split=str(d.get("split", "train")),
                version=version,
                switch=None if switch is None else int(switch),
            )
        except SpecError:
            raise
        except (KeyError, TypeError, ValueError) as exc:
            raise SpecError(f"malformed episode spec: {type(exc).__name__}: {exc}") from None

    @classmethod
    def from_json(cls, text: str) -> EpisodeSpec:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise SpecError(f"episode spec is not valid JSON: {exc}") from None
        if not isinstance(data, dict):
            raise SpecError("episode spec must be a JSON object")
        return cls.from_dict(data)
