"""One episode in the simulator: demonstrate it with a demo script, or replay recorded actions.

Generation demonstrates without rendering (physics is cheap), keeping the physics state before
every action; only a verified demo is then rendered, by restoring those states one by one, so a
failed demo never costs a rendered frame or a written byte and no step is simulated twice.
MuJoCo is deterministic: replaying the recorded actions reproduces the same states (tested).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from core import programs
from core.demo import DemoScript
from core.exam import SWITCH_DISTANCE
from core.programs import succeeded
from core.spec import EpisodeSpec
from core.success import Outcome
from oracle.ik import ArmIK, IKError
from oracle.scene import Scene
from oracle.skills import Skills


@dataclass
class Demo:
    spec: EpisodeSpec
    actions: np.ndarray  # (T, action size) float32, exactly what was executed
    states: np.ndarray  # (T, S) physics state (mjSTATE_INTEGRATION) before each action
    outcome: Outcome | None  # None when the script could not be executed (e.g. IK failed)
    success: bool
    failure: str = ""
    switch_step: int | None = None  # the first action after the instruction changed (a switched spec's)


def measure(scene: Scene, start: dict[str, tuple[float, float, float]]) -> Outcome:
    ee = scene.ee_pos()
    return Outcome(start, scene.positions(), (float(ee[0]), float(ee[1]), float(ee[2])), scene.turns())


def demonstrate(
    scene: Scene,
    ik: ArmIK,
    spec: EpisodeSpec,
    script: DemoScript,
    state: np.ndarray | None = None,
    settle: int = 0,
    prefix: Sequence[np.ndarray] = (),
    carrying: str | None = None,
) -> Demo:
    """Run `script` from the spec's poses, or from the physics `state` (an exam trial's start),
    after `settle` steps that hold the arm still (a profile's settle steps) and the actions of
    `prefix` (what ran before a plan changed course: the demo holds the actions after them, which
    first raise the hand over the objects, or go on with what the prefix left `carrying` in the
    hand, and its IK may start from the arm's home pose where the arm's own pose leads nowhere). A
    spec that switches (`EpisodeSpec.switch`) changes course on the way (`change_course`)."""
    if spec.switch is not None and not len(prefix):
        return change_course(scene, ik, spec, script, state, settle)
    scene.reset(spec)
    if state is not None:
        scene.set_physics_state(state)
    for _ in range(settle):
        scene.step(scene.interface.hold_action(spec.setup.robot_home))
    start = scene.positions()
    for action in prefix:
        scene.step(np.asarray(action))
    skills = Skills(scene, ik, spec)
    try:
        if len(prefix):
            skills.reseed = np.asarray(spec.setup.robot_home, float)
            if carrying is not None:
                skills.carry_on(carrying)
            else:
                skills.rise()  # a changed course leaves from above the objects, not through them
        else:
            skills.wait_still()  # plans are made around things at rest
        if len(spec.goals()) > 1:  # a goal after a motion that leaves the wrist turned (the knob's) may need IK from home
            skills.reseed = np.asarray(spec.setup.robot_home, float)
        script(skills, spec)
    except IKError as exc:
        return Demo(
            spec,
            np.asarray(skills.actions, np.float32).reshape(-1, spec.setup.interface.action_size),
            np.asarray(skills.states),
            None,
            False,
            str(exc),
        )
    outcome = measure(scene, start)
    ok = succeeded(spec, outcome)
    actions, states = np.asarray(skills.actions, np.float32), np.asarray(skills.states)
    return Demo(spec, actions, states, outcome, ok, "" if ok else "success predicate false")


def replay(scene: Scene, spec: EpisodeSpec, actions: np.ndarray, observe: Callable[[int], None] | None = None) -> Outcome:
    """Re-execute `actions` from the spec's initial state; `observe(t)` runs before action t."""
    scene.reset(spec)
    start = scene.positions()
    for t, action in enumerate(actions):
        if observe is not None:
            observe(t)
        scene.step(action)
    return measure(scene, start)


MOVED = 0.01  # m: how far the thing a program acts on must move before the hand counts as holding it
CARRIED = 0.05  # m: how high a carried object has risen when a switch that only changes where it goes comes
LATEST = 0.02  # m from where the hand takes hold of a thing: the latest a training switch comes (coming down, not yet closing)
ALONG = 0xA10  # the random stream of where on its approach a training episode changes course (`along`)
DESCENT = 0.75  # the share of training switches drawn from the descent, between the exam's step and LATEST (`along`)


def change_course(
    scene: Scene, ik: ArmIK, spec: EpisodeSpec, script: DemoScript, state: np.ndarray | None = None, settle: int = 0
) -> Demo:
    """A switched spec's demonstration: the first instruction's up to where its course and the
    second's part, then the oracle's replanned course to the second instruction's ask, by which it
    is judged. Where they part: when the second ask brings the object the first carries somewhere
    else (LIBERO-Goal's "… on the stove" for "… on the plate"), once it is carried CARRIED high
    (`carry_step`): before the grasp such a switch changes nothing the hand does, after it the hand
    carries it on to the new place. Otherwise, or where the oracle cannot carry it on (a bottle
    held across, asked onto a sloping rack), where the hand first comes within the exam's
    SWITCH_DISTANCE of what it takes hold of (`approach_step`, where an exam's switch rows change
    it): at a step drawn from the spec's seed and index up to where the hand is LATEST from it
    (`along`, mostly on the descent; at the exam's where the oracle cannot finish from the drawn one). An object taken is
    never put back: a switch to another object comes before the grasp."""
    first = demonstrate(scene, ik, replace(spec, switch=None), script, state, settle)
    if not first.success:
        return replace(first, spec=spec, failure=f"before its switch: {first.failure}")
    then = spec.after_switch()
    held = programs.named(spec.task.program).moved(spec, spec.target)
    asked = programs.named(then.task.program)
    if asked.brings and asked.moved(then, then.target) == held:
        carried = carry_step(scene, first, held, CARRIED)
        if carried is not None:
            demo = joined(first, carried, demonstrate(scene, ik, then, script, state, settle, first.actions[:carried], held))
            if demo.success:
                return replace(demo, spec=spec)
    to_hold = _to_hold(scene, first)
    step = _first_within(to_hold, SWITCH_DISTANCE)
    if not step:
        why = "the hand starts there" if step == 0 else "what it acts on never moves"
        return replace(first, spec=spec, success=False, failure=f"no approach to change course in ({why})")
    latest = max(step, _first_within(to_hold, LATEST) or step)
    for at in dict.fromkeys((along(spec, latest, step), step)):  # the drawn step, else the exam's
        demo = joined(first, at, demonstrate(scene, ik, then, script, state, settle, first.actions[:at]))
        if demo.success:
            break
    return replace(demo, spec=spec)


def along(spec: EpisodeSpec, latest: int, descent: int) -> int:
    """Where on its approach a training episode changes course: a step drawn from the spec's seed
    and index, DESCENT of them in [`descent`, `latest`] (from where an exam's switch rows change it,
    the hand 10 cm off, to LATEST), the rest anywhere in [1, `latest`]. At an exam's switch step a
    learned policy's hand is anywhere on its way, most often already over the original grocery and
    coming down: a course run's checkpoint trained on switches up to the oracle's 10 cm was there
    (1.4 cm off across), where no training switch had shown it a second instruction, and went on
    down (0/19 obeyed), and so did one whose switches were drawn evenly up to LATEST. Drawn here
    the state is shown, but showing it is not enough: on these switches a checkpoint trained as
    before still came down under the new name (scripts/switch_probe.py; docs/RESULTS_FACES.md)."""
    rng = np.random.default_rng([spec.seed, spec.index, ALONG])
    first = min(descent, latest) if rng.random() < DESCENT else 1
    return int(rng.integers(first, latest + 1))


def joined(first: Demo, step: int, then: Demo) -> Demo:
    """`first`'s actions before `step`, then `then`'s: judged as `then` is."""
    return Demo(
        then.spec,
        np.concatenate([first.actions[:step], then.actions]),
        np.concatenate([first.states[:step], then.states.reshape(-1, first.states.shape[1])]),  # none if its rise failed
        then.outcome,
        then.success,
        then.failure and f"switched at step {step}: {then.failure}",
        step,
    )


def carry_step(scene: Scene, demo: Demo, held: str, height: float) -> int | None:
    """The first action of `demo` at whose start `held` has risen `height` above where it stood;
    None if it never does."""
    start = None
    for t, state in enumerate(demo.states):
        scene.set_physics_state(state)
        z = float(scene.object_pos(held)[2])
        start = z if start is None else start
        if z - start > height:
            return t
    return None


def approach_step(scene: Scene, demo: Demo, within: float) -> int | None:
    """The first action of `demo` at whose start the hand is within `within` of where it takes hold
    of what it acts on first: the object it carries somewhere, else the target (a grocery, a drawer,
    the knob). Where it takes hold is the hand's position when that thing first moves, whatever the
    skill (a grasp, a push, a pull on a handle, a turn). There the approach has committed, and a new
    instruction still means a course to change: nothing is held yet. None if the thing never moves
    or the hand never comes so near before it does."""
    return _first_within(_to_hold(scene, demo), within)


def _to_hold(scene: Scene, demo: Demo) -> np.ndarray | None:
    """The hand's distance, at the start of each action of `demo` before it, from where it takes
    hold of what it acts on first (`approach_step`): one replay of its states for every distance
    asked of it. None if that thing never moves."""
    spec = demo.spec
    first = programs.named(spec.task.program).moved(spec, spec.target)
    path = []
    for state in demo.states:
        scene.set_physics_state(state)
        path.append((scene.ee_pos().copy(), scene.object_pos(first).copy()))
    start = path[0][1] if path else None
    moved = next((t for t, (_, at) in enumerate(path) if np.linalg.norm(at - start) > MOVED), None)
    if moved is None:
        return None
    hold = path[moved][0]
    return np.array([np.linalg.norm(ee - hold) for ee, _ in path[:moved]])


def _first_within(to_hold: np.ndarray | None, within: float) -> int | None:
    """The first action at whose start the hand is within `within` of where it takes hold."""
    return None if to_hold is None else next((t for t, d in enumerate(to_hold) if d < within), None)
