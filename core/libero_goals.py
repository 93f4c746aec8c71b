"""A LIBERO task's goal as our programs (core/programs.py): what the oracle does, goal by goal, and
in which order, where LIBERO's BDDL goal asks several things at once (LIBERO-10's "put both ...",
"... and close it"). LIBERO leaves the order free; the oracle's is the one its skills manage:

1. things brought to a place (a burner, the table's region right of the plate, a drawer) before
   things brought onto or into another thing: a mug's handle, over the plate's edge, is where the
   pudding beside that plate comes down;
2. then the furniture's motions: the knob turned once the pot stands on the burner (from the
   turned knob the hand's way to the pot sweeps the table), the drawer shut once the bowl is in it.

LIBERO's predicates read as programs: `In(x, <thing>_contain_region)` carries x into that thing
(`pick_place`), `On(x, <thing>)` onto it (`pick_place_on`); `In`/`On` of a region of the furniture
or the table, a place of the world's kinds (its site, or the name LIBERO's goals give it), brings x
there (`place_in` where the program judging LIBERO's `In` is asked, else `place`); `Turnon`,
`Close`, `Open` of a place are those programs. Two things brought to one place stand side by side
as its kind says (`Kind.side_by_side`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from core import programs
from core.catalog import Kind
from core.libero import Problem
from core.spec import THEN, TaskSpec
from core.worlds import World

CONTAIN = "_contain_region"  # LIBERO's region of a container object (a basket) that `In` asks for


@dataclass(frozen=True)
class Goal:
    """One goal as a program: its target (an instance of the problem, or a place's kind) and params."""

    program: str
    target: str
    params: dict[str, Any] = field(default_factory=dict)


def goals(problem: Problem, world: World) -> tuple[Goal, ...] | None:
    """The problem's goals as programs in the order the oracle does them, or None where a predicate
    asks for what our programs or the world's places do not do. A goal its
    initial state already holds is left out: LIBERO's every state of KITCHEN_SCENE8 has the stove on,
    near its knob's stop, where a turn moves it too little for our scorer (which judges a turn from
    where the knob started)."""
    held = set(problem.init)  # a goal the problem starts with already met (KITCHEN_SCENE8's stove, on) is none to do
    found = [_goal(predicate, problem, world) for predicate in problem.goal if predicate not in held]
    if any(g is None for g in found):
        return None
    ordered = sorted((g for g in found if g is not None), key=_rank)
    return tuple(_side_by_side(ordered, problem, world))


def task(goals: tuple[Goal, ...]) -> TaskSpec:
    """Goals as one spec's task: the first's program and params, the others in `params["then"]`
    (core/spec.py EpisodeSpec.goals); the first's target is the spec's."""
    first, *rest = goals
    then = [{"program": g.program, "target": g.target, "params": g.params} for g in rest]
    return TaskSpec(first.program, params={**first.params, THEN: then} if then else dict(first.params))


def _goal(predicate: tuple[str, ...], problem: Problem, world: World) -> Goal | None:
    name, *args = predicate
    said = name.lower()
    if said in ("in", "on") and len(args) == 2:
        moved, where = args
        if where.endswith(CONTAIN) and where.removesuffix(CONTAIN) in problem.objects and said == "in":
            return Goal("pick_place", moved, {"destination": where.removesuffix(CONTAIN)})
        if where in problem.objects and said == "on":
            return Goal("pick_place_on", moved, {"destination": where})
        place = _place(where, world)
        if place is None:
            return None
        program = _motion(name) if said == "in" else "place"
        return Goal(program, place, {"object": moved}) if program else None
    if len(args) == 1:
        place, program = _place(args[0], world), _motion(name)
        return Goal(program, place) if place and program else None
    return None


def _place(name: str, world: World) -> str | None:
    """The world's kind of a place LIBERO's goals name: its site's name, or the name they give it."""
    return next((k.name for k in world.kinds.values() if k.spot and name in (k.spot.site, k.spot.goal_name)), None)


def _motion(predicate: str) -> str | None:
    """The program judged as LIBERO's `predicate` (Close, Turnon, In of a drawer's region)."""
    return next((p.name for p in programs.PROGRAMS.values() if (p.libero or "").lower() == predicate.lower()), None)


def _rank(goal: Goal) -> int:
    """The order's rule (the module's docstring): to a place, onto or into a thing, the furniture's motions."""
    program = programs.named(goal.program)
    if not program.held:
        return 2
    return 0 if "object" in goal.params else 1


def _side_by_side(ordered: list[Goal], problem: Problem, world: World) -> list[Goal]:
    """Two things brought to one place: each `Kind.side_by_side` from its centre, the first one way."""
    where = [g.params.get("destination") or (g.target if "object" in g.params else None) for g in ordered]
    placed = []
    for goal, place in zip(ordered, where):
        shared = [i for i, p in enumerate(where) if p is not None and p == place]
        kind = _kind(place, problem, world) if len(shared) == 2 else None
        if kind is None or kind.side_by_side is None:
            placed.append(goal)
            continue
        placed.append(Goal(goal.program, goal.target, {**goal.params, "at": kind.beside(shared.index(len(placed)))}))
    return placed


def _kind(place: str | None, problem: Problem, world: World) -> Kind | None:
    if place is None:
        return None
    return world.kind(problem.objects[place]) if place in problem.objects else world.kind(place)
