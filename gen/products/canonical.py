"""`python -m gen.canonical world=libero_object` (or libero_spatial, libero_goal, or a world of
LIBERO-10's, whose tasks span several: libero_10_living_room takes those set in its living room), or
`suite=<a LIBERO-PRO suite>` (libero_object_swap, libero_spatial_lan, ...): an exam on LIBERO's
own initial states.

Its task rows are exactly a LIBERO suite's tasks: LIBERO's initial states (every one of the 50
per task, or `states=` of them drawn with `seed=`), LIBERO's instructions, the rollout horizon
and settle steps lerobot's LIBERO environment uses. On each state the swap rows are the world's
referent type's (its `canonical` design of the task: in LIBERO-Object every other grocery, in
LIBERO-Spatial the other bowl, named by where it stands), and occ and nonsense rows follow, as
in every exam (core/exam.py). A LIBERO-trained policy's task rate here is its published LIBERO
number; its swap rate is whether it reads the instruction. The `position` policy is the
shortcut LIBERO's layouts reward: it knows the scene and fetches what that task's target was.

A LIBERO-PRO suite perturbs its base suite (objects swapped, moved, recoloured or added; the
instruction paraphrased or another target named) with its own BDDL problems and initial states;
its world is its base suite's. Its scene holds the suite's objects, built from their LIBERO
models (referents/scenery.py), and each task row is given the instruction the suite's BDDL file
writes in its `(:language ...)` line where that differs from the base task's, which is what the
perturbation is (LIBERO-PRO keeps the base task's file name, from which LIBERO's benchmark, and
the runners that use it, take the instruction: they never deliver it); elsewhere the base task's
instruction. `exam.json` records, per task, the file, its language line, the file-name
instruction and the one delivered.

The states are LIBERO's exactly (joints set by name from LIBERO's state vectors), so the first
settle steps show what they show in LIBERO: objects placed slightly into the floor pop up and
settle.
"""

from __future__ import annotations

import re
import time
from collections import Counter
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Optional

import numpy as np

from core import exam, libero, libero_goals, profiles, programs, worlds
from core.profiles import STATE_KEY, TASK_KEY
from core.rotations import yaw_of
from core.spec import FAST, LOOKS, Counterfactual, EpisodeSpec, SceneObject, Setup
from gen.config import check_seed
from gen.planning.audit import audit
from gen.products.exam import take_hint
from jobs.cli import UserError
from jobs.output import check_output
from jobs.partial import staging
from referents import registry
from referents.design import Design
from referents.registry import Referent

if TYPE_CHECKING:
    from oracle.scene import Scene

ON_SCENE_MARGIN = 0.2  # m beyond a world's reach where LIBERO's regions may still stand


@dataclass
class CanonicalOptions:
    world: Optional[str] = None  # a LIBERO world (core/worlds/), its suite's tasks, or libero_10 (all ten); default libero_object
    states: int = 50  # initial states per task (LIBERO has 50, some LIBERO-PRO suites 10); fewer are drawn with `seed`
    seed: int = 0
    image_size: int = 256  # the cameras' frames, pixels (the exam's policy side)
    out: Optional[str] = None  # default datasets/<suite>-canonical
    overwrite: bool = False
    suite: Optional[str] = None  # a LIBERO-PRO suite of the world's (its world is inferred): libero_object_swap, ...
    tasks: Optional[int] = None  # only the first this many covered tasks (a quick look); default all
    look: str = FAST  # fast | full: how the exam's cameras draw (core/spec.py LOOKS)
    switches: int = 1  # switch rows per trial (the instruction changed mid-course, core/exam.py); 0: none


@dataclass(frozen=True)
class Suite:
    """A LIBERO suite as an exam: its world, the referent type that lays its tasks out, and the
    tasks it covers (with why the others are not)."""

    name: str
    world: worlds.World
    referent: Referent
    tasks: tuple[str, ...]
    left_out: dict[str, str]  # task -> why it is not covered

    def problem(self, task: str) -> libero.Problem:
        return libero.problem(self.name, task)

    def inventory(self) -> tuple[tuple[str, int], ...]:
        """The bodies its scene compiles: the referent's, every kind its covered tasks place, as
        many as any task places, and the places on furniture their goals name."""
        most = Counter(dict(self.referent.assets()))
        for task in self.tasks:
            for kind, n in Counter(self.problem(task).objects.values()).items():
                most[kind] = max(most[kind], n)
            design = self.referent.code.canonical(self.referent.config, self.problem(task))
            for p in design.placements if design else ():
                if self.world.kind(p.candidate.kind).is_site:
                    most[p.candidate.kind] = max(most[p.candidate.kind], 1)
        return tuple(sorted(most.items()))

    def instruction(self, task: str, base: str) -> str:
        """The instruction a task row is given: the BDDL's `(:language)` line where the suite changed
        it from its base task's (a paraphrase, another target), else `base` (the base task's)."""
        ours = self.problem(task).language
        theirs = libero.problem(self.world.suite, libero.base_task(self.name, task)).language
        return ours if ours and _words(ours) != _words(theirs) else base

    def swaps(self, task: str, design: Design, delivered: str) -> tuple[tuple[Counterfactual, ...], dict[str, str]]:
        """The swaps of a task row that says `delivered`: each the delivered instruction with the words
        naming the target changed to another's, the suite's wording kept (where it is LIBERO's own,
        the design's swaps as they are); and those left out, each with why (swap target -> reason):
        where the wording does not say the target's words, and in a suite that names another target
        than its base task (`_task`), the swap back to the base task's own target, which LIBERO's
        layout alone leads a policy to that ignores the words."""
        if delivered == design.instruction:
            return design.counterfactuals, {}
        base = libero.problem(self.world.suite, libero.base_task(self.name, task))
        named = base.goal[0][1] if base.goal and len(base.goal[0]) > 1 else None
        base_target = {named, base.objects.get(named)} - {None}  # a design names a target by instance or by category
        kept, left = [], {}
        for cf in design.counterfactuals:
            old, new = cf.changed
            found = re.search(_loosely(old), delivered, re.IGNORECASE)
            if found is None:
                left[cf.target] = f"the suite's instruction ({delivered!r}) does not say {old!r}, so no word of it names another"
            elif cf.target in base_target and cf.target != design.target:
                left[cf.target] = f"it names the base task's own {new}, which LIBERO's layout leads to whatever the words"
            else:
                kept.append(replace(cf, instruction=delivered[: found.start()] + new + delivered[found.end() :]))
        return tuple(kept), left


ARTICLES = ("the", "a", "an")


def _loosely(phrase: str) -> str:
    """A pattern of `phrase`'s words that lets a paraphrase drop or add its articles ("between the
    plate and ramekin" says "between the plate and the ramekin")."""
    words = [w for w in phrase.split() if w.lower() not in ARTICLES]
    article = rf"(?:(?:{'|'.join(ARTICLES)})\s+)?"
    leading = article if phrase.split()[0].lower() in ARTICLES else ""
    return r"\b" + leading + rf"\s+{article}".join(map(re.escape, words)) + r"\b"


def _words(text: str) -> list[str]:
    return text.lower().replace(".", " ").split()


def _libero_worlds() -> str:
    """What `world=` takes here: each world that lays out a LIBERO suite, and each suite whose tasks
    span several (libero_10)."""
    spanning = [suite for suite, spanned in _base_suites().items() if len(spanned) > 1]
    return ", ".join([*spanning, *(name for name in worlds.names() if worlds.world(name).suite)])


def world_suite(name: str) -> str:
    """The LIBERO suite a canonical exam's `world=` names: the world's own, or a suite whose tasks span
    several worlds (libero_10); one line (UserError) for any other name."""
    if len(_base_suites().get(name, [])) > 1:
        return name
    try:
        suite = worlds.world(name).suite
    except worlds.UnknownWorld:
        raise UserError(f"unknown world {name!r}; canonical exams are LIBERO's: {_libero_worlds()}") from None
    if not suite:
        raise UserError(f"world {name} has no LIBERO suite; canonical exams are LIBERO's: {_libero_worlds()}")
    return suite


def _base_suites() -> dict[str, list[str]]:
    """Each LIBERO suite a world lays out -> those worlds (LIBERO-10's tasks span several)."""
    found: dict[str, list[str]] = {}
    for name in worlds.names():
        if worlds.world(name).suite and not worlds.world(name).pro_suite:
            found.setdefault(worlds.world(name).suite, []).append(name)
    return found


def _all_suites() -> str:
    return ", ".join(s for base in _base_suites() for s in libero.suites(base))


def _canonical_worlds() -> str:
    return ", ".join(name for name in worlds.names() if _task_type(name) is not None)


def _task_type(world: str) -> Referent | None:
    """The referent type that lays out a world's LIBERO tasks (its `canonical` hook): one of the
    world's own types, or a spec there that does nothing else (registry.tasks_only); or None."""
    loaded = [*map(registry.load, registry.of_world(world)), *(registry.load("", p) for p in registry.tasks_only(world))]
    return next((r for r in loaded if r.code.canonical is not None), None)


def _why_not(world: worlds.World, referent: Referent, suite: str, task: str) -> str | None:
    """Why a task of a suite is not covered (None: it is): a model LIBERO-PRO does not ship, furniture
    other than the world's, a task our skills cannot do, no initial states, its destination moved out of reach."""
    problem = libero.problem(suite, task)
    missing = sorted(set(problem.objects.values()) - set(world.kinds))
    if missing:
        shipped = [k for k in missing if any(libero.assets_root().glob(f"*/{k}/{k}.xml"))]
        if shipped:
            return f"world {world.name} has no kind for {', '.join(shipped)} yet (core/libero.py)"
        return f"no model of {', '.join(missing)} is installed (LIBERO-PRO registers it but ships no file)"
    furniture = {f.fixture.kind for f in world.fixtures}
    tables = {f for f in problem.fixtures.values() if f.endswith("table")}  # the world's own table (LIBERO's kinds of it)
    other = sorted(set(problem.fixtures.values()) - furniture - tables - {"floor"})
    if other:
        return f"its furniture ({', '.join(other)}) is not world {world.name}'s"
    moved = _moved_fixtures(problem, libero.problem(world.suite, libero.base_task(suite, task)))
    if moved and world.pro_suite != suite:
        return (
            f"LIBERO-PRO moves its {', '.join(moved)}, and no world stands the scene as {suite} lays it out "
            f"(a twin world with pro_suite={suite}, core/worlds/)"
        )
    assert referent.code.canonical is not None
    design = referent.code.canonical(referent.config, problem)
    if design is None:
        goal = f"{problem.goal[0][0]} {' '.join(problem.goal[0][1:])}"
        if len(problem.goal) > 1 and libero_goals.goals(problem, world) is not None:  # a LIBERO-10 task our programs do
            return (
                f"referent type {referent.name} does not lay it out ({goal}, ...: our programs do its goals; a place it names "
                f"has no slot in the type's layout of world {world.name})"
            )
        return f"our skills cannot do it ({goal}: docs/LIBERO.md says which tasks each world covers)"
    carried = design.task.params.get("object", design.target) if design.task else design.target
    carried_kind = world.kind(next(p.candidate.kind for p in design.placements if p.id == carried))
    held = design.task is None or programs.named(design.task.program).held  # not slid along the table
    if held and not carried_kind.is_site and not carried_kind.graspable():
        return f"its {carried_kind.name} is wider than the Panda's fingers open"
    if not len(libero.initial_states(suite, task)):
        return "its initial-state file is empty"
    for name in problem.goal[0][1:]:
        instance = name.removesuffix("_contain_region")
        regions = [pred[2] for pred in problem.init if len(pred) == 3 and pred[1] == instance]
        if instance in problem.objects and regions and any(r.split("_", 1)[-1] in problem.regions for r in regions):
            if not _on_scene(world, *problem.centre(problem.region_of(instance))):
                return f"LIBERO-PRO parks {instance}, which the goal names, off the scene"
    return None


def _moved_fixtures(problem: libero.Problem, base: libero.Problem) -> list[str]:
    """The fixtures a perturbed problem stands in another region than its base task does."""
    where = {pred[1]: pred[2] for pred in base.init if len(pred) == 3 and pred[1] in base.fixtures}
    placed = [pred for pred in problem.init if len(pred) == 3 and pred[1] in problem.fixtures]
    return sorted(name for _, name, region in placed if where.get(name, region) != region)


def _laid_out(world: worlds.World, suite: str) -> worlds.World:
    """The world that stands `world`'s scenes as `suite` lays them out: its LIBERO-PRO twin where that
    suite moves the furniture (World.pro_suite), else `world` itself."""
    twins = (worlds.world(n) for n in worlds.names())
    return next((w for w in twins if w.pro_suite == suite and (w.suite, w.scenes) == (world.suite, world.scenes)), world)


def _on_scene(world: worlds.World, x: float, y: float) -> bool:
    """Whether a place is on the world's scene (LIBERO-PRO parks the objects a suite takes away
    metres off it, e.g. at x = 10 m): its reach, with a margin for LIBERO's regions at its edges."""
    x0, x1, y0, y1 = world.reach
    return x0 - ON_SCENE_MARGIN <= x <= x1 + ON_SCENE_MARGIN and y0 - ON_SCENE_MARGIN <= y <= y1 + ON_SCENE_MARGIN


def suite_of(options: CanonicalOptions) -> Suite:
    """The options' suite, checked (bad input: UserError, one line)."""
    name = options.suite or (options.world or "libero_object")
    base = libero.base_suite(name)
    if options.suite and base not in _base_suites():
        raise UserError(f"unknown suite {name!r}; LIBERO's and LIBERO-PRO's suites with their files installed: {_all_suites()}")
    world_suite(options.world or base)
    world = worlds.world(options.world or base)
    try:
        world.requires()
    except worlds.WorldUnavailable as exc:
        raise UserError(f"world={world.name}: {exc}") from None
    if options.world and options.suite and base != world.suite:
        raise UserError(f"suite={options.suite} perturbs {base}, not world={options.world}: leave world= out")
    if options.world and not options.suite:
        name = world.pro_suite or world.suite  # its own suite's tasks, those of its scenes where the suite's span several worlds
    if name not in libero.suites(world.suite):
        raise UserError(f"unknown suite {name!r}; LIBERO's and LIBERO-PRO's suites with their files installed: {_all_suites()}")
    if world.pro_suite and name != world.pro_suite:
        raise UserError(f"world {world.name} stands its scenes as {world.pro_suite} lays them out: suite={world.pro_suite} only")
    world = _laid_out(world, name)
    referent = _task_type(world.name)
    if referent is None:
        raise UserError(
            f"world {world.name} has no referent type that lays out LIBERO's tasks yet; canonical exams: {_canonical_worlds()}"
        )
    why = {task: _why_not(world, referent, name, task) for task in libero.tasks(name) if world.stands(task)}
    if not why:
        raise UserError(f"suite {name} sets none of its tasks in world {world.name}")
    covered = tuple(task for task, reason in why.items() if reason is None)
    if not covered:
        reasons = Counter(why.values()).most_common(1)[0][0]
        raise UserError(f"suite {name} has no task our skills and LIBERO's installed models can do: {reasons}")
    return Suite(name, world, referent, covered, {t: r for t, r in why.items() if r is not None})


def _spanned(options: CanonicalOptions) -> list[str]:
    """The worlds of a suite whose tasks stand in several (LIBERO-10's: `world=libero_10`, or one of its
    LIBERO-PRO suites without `world=`); [] for a suite of one world or a world named."""
    base = libero.base_suite(options.suite or options.world or "")
    spanned = _base_suites().get(base, [])
    return spanned if len(spanned) > 1 and options.world in (None, base) else []


def suites_of(options: CanonicalOptions) -> tuple[tuple[Suite, ...], dict[str, str]]:
    """The options' suite, one per world its tasks stand in (LIBERO-10's span six), with the tasks of
    worlds that lay out none of them and why (task -> reason)."""
    spanned = _spanned(options)
    if not spanned:
        return (suite_of(options),), {}
    found, left = [], {}
    for world in spanned:
        try:
            found.append(suite_of(replace(options, world=world)))
        except UserError as exc:  # a world none of whose tasks is laid out: each of its tasks, why
            name = options.suite or worlds.world(world).suite
            left |= {task: f"world {world}: {exc}" for task in libero.tasks(name) if worlds.world(world).stands(task)}
    if not found:
        tasks = libero.tasks(options.suite or libero.base_suite(options.world or ""))
        why = next(iter(left.values()), f"none of its tasks is set in a scene of ours (its first: {tasks[0]})")
        raise UserError(f"no world of {options.suite or options.world} lays out its tasks: {why}")
    return tuple(found), left


def _options(options: CanonicalOptions) -> tuple[tuple[Suite, ...], dict[str, str], Path]:
    suites, left = suites_of(options)
    if options.tasks is not None:
        if options.tasks < 1:
            raise UserError(f"tasks must be at least 1, got {options.tasks}")
        kept, room = [], options.tasks
        for suite in suites:
            if room > 0:
                kept.append(replace(suite, tasks=suite.tasks[:room]))
                room -= len(kept[-1].tasks)
        suites = tuple(kept)
    check_seed(options.seed)
    fewest = min(len(libero.initial_states(suite.name, t)) for suite in suites for t in suite.tasks)
    if not 1 <= options.states <= fewest:
        raise UserError(
            f"states must be between 1 and {fewest} ({suites[0].name}'s initial states per task), got {options.states}"
        )
    if not 16 <= options.image_size <= worlds.MAX_IMAGE_SIZE or options.image_size % 2:
        raise UserError(f"image_size must be an even number of pixels in [16, {worlds.MAX_IMAGE_SIZE}], got {options.image_size}")
    if options.look not in LOOKS:
        raise UserError(f"look must be one of {', '.join(LOOKS)}, got {options.look!r}")
    if options.switches < 0:
        raise UserError(f"switches must be 0 or more, got {options.switches}")
    out = Path(options.out or f"datasets/{suites[0].name}-canonical")
    check_output(out, options.overwrite)
    return suites, left, out


def trial_spec(suite: Suite, task: str, index: int, seed: int, setup: Setup) -> EpisodeSpec:
    """A LIBERO task's scene as an episode spec (the referent type's `canonical` design of it):
    its objects under the design's ids, each where the task's region puts it until the initial
    state poses it, the instruction the suite delivers, the swaps."""
    referent, world = suite.referent, suite.world
    assert referent.code.canonical is not None
    design = referent.code.canonical(referent.config, suite.problem(task))
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
    delivered = suite.instruction(task, libero.language(libero.base_task(suite.name, task)))
    return EpisodeSpec(
        referent=referent.name,
        index=index,
        seed=seed,
        objects=tuple(objects),
        target=design.target,
        instruction=delivered,
        template=design.template,
        counterfactuals=suite.swaps(task, design, delivered)[0],
        assets=suite.inventory(),
        task=design.task or referent.config.task,
        setup=setup,
        split="exam",
    )


def covered(referent: Referent, world: worlds.World) -> list[str]:
    """The base suite's tasks the referent type can lay out."""
    return list(suite_of(CanonicalOptions(world=world.name)).tasks)


def build(options: CanonicalOptions) -> None:
    suites, left_worlds, out = _options(options)
    from tqdm import tqdm

    from gen.products.exam import first_frame, switch_rows
    from oracle.ik import ArmIK
    from oracle.render import Cameras
    from oracle.scene import scene_for

    started = time.perf_counter()
    rng = np.random.default_rng(options.seed)
    chosen = {
        task: sorted(rng.choice(len(libero.initial_states(suite.name, task)), options.states, replace=False).tolist())
        for suite in suites
        for task in suite.tasks
    }
    rows, specs, without, reports, setups = [], [], {}, {}, {}
    bar = tqdm(total=sum(map(len, chosen.values())), desc=f"{suites[0].name} initial states", unit="state")
    for suite in suites:  # a scene, its renderer and its IK per world
        world = suite.world
        profile = profiles.named(world.profiles[0])
        setup = Setup(options.image_size, 20, profile.camera_names, world.robot_home, profile.name, world.name, options.look)
        scene = scene_for(suite.inventory(), profile.name, world.name, options.look)
        ik = ArmIK(np.asarray(world.robot_home), world.name)
        cameras = Cameras(scene, setup.image_size, setup.cameras)
        first = len(specs)
        for task in suite.tasks:
            for s in chosen[task]:
                spec = load_state(scene, suite, task, s, setup, len(specs), options.seed)
                values = {a.id: a.value for a in suite.referent.alternatives(spec)}
                ee = [float(v) for v in scene.ee_pos()]
                state = scene.physics_state().astype(np.float64).tolist()
                settled = scene.settled(spec)
                seen = first_frame(cameras, spec)
                switched, why = switch_rows(scene, ik, suite.referent, spec, state, len(specs), options.switches)
                if why:
                    without[str(len(specs))] = why
                rows += exam.trial_rows(len(specs), spec, values, state, world.episode_steps, ee, settled, switched, seen)
                specs.append(spec)
                bar.update()
        cameras.close()
        reports[world.name] = audit(suite.referent, specs[first:])
        setups[world.name] = setup
    bar.close()
    with staging(out) as root:
        root.mkdir(parents=True)
        header = _header(options, suites, setups, chosen, reports, left_worlds)
        exam.write(root, rows, {**header, **({exam.NO_SWITCH: without} if without else {})})
    laid_out = sum(len(suite.tasks) for suite in suites)
    omitted = len(left_worlds) + sum(len(suite.left_out) for suite in suites)
    left = f"; left out: {omitted} task(s) (exam.json says why)" if omitted else ""
    print(
        f"wrote an exam of {len(specs)} LIBERO initial states ({laid_out} tasks x {options.states}) of {suites[0].name} "
        f"to {out} in {time.perf_counter() - started:.1f} s{left}\n{take_hint(out)}"
    )


def load_state(scene: Scene, suite: Suite, task: str, state: int, setup: Setup, index: int = 0, seed: int = 0) -> EpisodeSpec:
    """Put `scene` in a LIBERO task's initial state number `state` (joints set by name from
    LIBERO's state vector); returns the trial's spec, its objects posed as that state poses them."""
    problem = suite.problem(task)
    vector = libero.initial_states(suite.name, task)[state]
    spec = _posed(trial_spec(suite, task, index, seed, setup), vector, problem, suite.world)
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
    parked = {o.id for o in objects if not _on_scene(world, o.pos[0], o.pos[1])}
    swaps = tuple(c for c in spec.counterfactuals if c.target not in parked)  # no swap names what is not there
    return replace(spec, objects=(*objects, *spec.objects[len(objects) :]), counterfactuals=swaps)  # places on furniture stay


def _header(options: CanonicalOptions, suites: tuple[Suite, ...], setups: dict[str, Setup], chosen: dict, reports: dict,
            left_worlds: dict[str, str]) -> dict:  # fmt: skip
    """exam.json's fields. An exam of a suite spanning several worlds (LIBERO-10's) lists them under
    `worlds` (each trial's spec names its own), and its referent's spec and audit per world."""
    first = suites[0]
    setup, referent = setups[first.world.name], first.referent
    features = profiles.named(setup.profile)
    several = bool(_spanned(options))
    world = first.world.suite if several else first.world.name
    if first.name == first.world.suite:
        named = f"world={world}"
    else:  # a LIBERO-PRO suite: and the one world taken, where its base suite's tasks span several
        named = f"suite={first.name}" + ("" if several or len(_base_suites()[first.world.suite]) == 1 else f" world={world}")
    tasks = {}
    for suite in suites:
        for task in suite.tasks:
            problem, base = suite.problem(task), libero.base_task(suite.name, task)
            delivered = suite.instruction(task, libero.language(base))
            design = suite.referent.code.canonical(suite.referent.config, problem)
            assert design is not None  # a covered task
            tasks[task] = {
                "bddl": f"bddl_files/{suite.name}/{task}.bddl",
                "language_line": problem.language,
                "file_name_instruction": libero.language(task),
                "instruction": delivered,
                "base_task": base,
            }
            left = suite.swaps(task, design, delivered)[1]
            if left:
                tasks[task]["left_out_swaps"] = left
    where = {"worlds": [s.world.name for s in suites]} if several else {"world": first.world.name}
    return {
        "referent": referent.name,
        "seed": options.seed,
        "split": "exam",
        "command": f"python -m gen.canonical {named} states={options.states} seed={options.seed} image_size={options.image_size}"
        + (f" tasks={options.tasks}" if options.tasks else "")
        + (f" switches={options.switches}" if options.switches != 1 else ""),
        "profile": setup.profile,
        **where,
        "canonical": {
            "suite": first.name,
            "base_suite": first.world.suite,
            "states": {task: states for task, states in chosen.items()},
            "tasks": tasks,
            "left_out": {task: why for suite in suites for task, why in suite.left_out.items()} | left_worlds,
            "episode_steps": max(s.world.episode_steps for s in suites),
            "settle_steps": features.settle_steps,
        },
        "observation": {
            "keys": [features.image_key(c) for c in setup.cameras] + [STATE_KEY],
            "instruction": f"the `instruction` column of trials.parquet; info['instruction'] in the gymnasium env; "
            f"`{TASK_KEY}` in python -m eval's observation dicts",
            "image_size": setup.image_size,
            "fps": setup.fps,
            "state_names": list(features.state_names),
            "action_names": list(features.action_names),
            "action": features.action_meaning,
            "mirrored": features.mirrored,
            "settle_steps": features.settle_steps,
        },
        **(
            {"referent_spec": {s.world.name: asdict(s.referent.config) for s in suites}, "audit": reports}
            if several
            else {"referent_spec": asdict(referent.config), "audit": reports[first.world.name]}
        ),
    }
