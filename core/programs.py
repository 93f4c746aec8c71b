"""Motor programs, one record each: what an instruction asks the hand to do to what it names.

A program's record is everything the project knows of it: what the instruction's target is (the
thing moved, the place something is brought to, or the part of a piece of furniture a motion
moves), which task parameters it reads, whether the hand carries what it moves, how our scorer
judges it (core/success.py), the LIBERO goal predicate it is, and its demonstration over the
skills (core/demo.py). Every other module reads the record (`named`); none branches on a name.
A task of more goals than one (LIBERO-10's "put both ...", "... and close it") is programs in
turn: the spec's `task.params["then"]` lists the goals after the first (core/spec.py
`EpisodeSpec.goals`); the oracle performs each, and the task is done when every goal is.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

from core import success
from core.demo import Skills
from core.spec import EpisodeSpec
from core.success import Outcome

Predicate = Callable[[EpisodeSpec, Outcome, str], bool]  # (spec, outcome, target) -> done
Names = Literal["moved", "place", "part"]

CARRY_LIFT = 0.1  # how high a thing carried somewhere is lifted before the hand carries it


@dataclass(frozen=True)
class Program:
    """One motor program. `names`: what the instruction's target is — `moved`, the thing the
    program moves (a grocery picked up); `place`, where it brings `params.object` (a plate, a
    drawer); `part`, the part of a piece of furniture the motion moves (a drawer, the stove's knob).
    `needs`: the task parameters it reads (`object`: what is brought; `destination`: where the
    target goes). `held`: the hand carries what it moves (not slid along the table, not a part of
    the furniture). `libero`: LIBERO's goal predicate where the program is one of its own; None
    where it follows where the thing goes (`In` a container's region, `On` anything else) or LIBERO
    has none."""

    name: str
    names: Names
    judge: Predicate
    perform: Callable[[Skills, EpisodeSpec], None]
    needs: tuple[str, ...] = ()
    held: bool = True
    libero: str | None = None

    def moved(self, spec: EpisodeSpec, target: str) -> str:
        """The object the program moves when it acts on `target`: what it brings there, else `target`."""
        return spec.task.params["object"] if "object" in self.needs else target

    @property
    def brings(self) -> bool:
        """The target is where the program brings `params.object`."""
        return self.names == "place"

    @property
    def carries(self) -> bool:
        """The hand takes one thing and carries it to the target (a grocery to a plate): how far it got
        is a stage of its own (the scorer's carry probe)."""
        return self.brings and self.held

    @property
    def lands(self) -> bool:
        """The hand lands on what the instruction names (so it could land on any other object instead)."""
        return self.names == "moved"


def _pick(skills: Skills, spec: EpisodeSpec) -> None:
    skills.grasp(spec.target)
    skills.lift()


def _push(skills: Skills, spec: EpisodeSpec) -> None:
    skills.push(spec.target)


def _carry(skills: Skills, spec: EpisodeSpec) -> None:
    """Grasp the target and put it where the world carries it (a basket, a plate; `params.at` from
    its centre, where a task brings two things to it)."""
    skills.grasp(spec.target)
    skills.lift(CARRY_LIFT)
    skills.place(spec.task.params["destination"], _at(spec))


def _place(skills: Skills, spec: EpisodeSpec) -> None:
    """Bring the object to the named place (across a sloping shelf's slope, to be laid along it;
    `params.at` from its centre, where a task brings two things to it)."""
    skills.grasp(spec.task.params["object"], onto=spec.target)
    skills.lift(CARRY_LIFT)
    skills.place(spec.target, _at(spec))


def _at(spec: EpisodeSpec) -> tuple[float, float] | None:
    at = spec.task.params.get("at")
    return None if at is None else tuple(at)


def _place_in(skills: Skills, spec: EpisodeSpec) -> None:
    skills.put_in(spec.task.params["object"], spec.target)


def _open(skills: Skills, spec: EpisodeSpec) -> None:
    skills.pull_open(spec.target)


def _close(skills: Skills, spec: EpisodeSpec) -> None:
    skills.shut(spec.target)


def _turn_on(skills: Skills, spec: EpisodeSpec) -> None:
    skills.turn_on(spec.target)


def _push_to(skills: Skills, spec: EpisodeSpec) -> None:
    skills.push_to(spec.task.params["object"], spec.target)


PROGRAMS: dict[str, Program] = {
    p.name: p
    for p in (
        Program("pick", "moved", success.lifted, _pick),
        Program("push", "moved", success.pushed, _push, held=False),
        Program("place", "place", success.placed, _place, ("object",)),
        Program("pick_place", "moved", success.contained, _carry, ("destination",)),
        Program("pick_place_on", "moved", success.on, _carry, ("destination",)),
        Program("open", "part", success.opened, _open, held=False, libero="Open"),
        Program("close", "part", success.closed, _close, held=False, libero="Close"),
        Program("turn_on", "part", success.turned_on, _turn_on, held=False, libero="Turnon"),
        Program("place_in", "place", success.put_in, _place_in, ("object",), libero="In"),
        Program("push_to", "place", success.pushed_to, _push_to, ("object",), held=False, libero="On"),
    )
}


class UnknownProgram(ValueError):
    pass


def named(name: str) -> Program:
    try:
        return PROGRAMS[name]
    except KeyError:
        raise UnknownProgram(f"no motor program {name!r}; known: {', '.join(PROGRAMS)}") from None


def perform(skills: Skills, spec: EpisodeSpec) -> None:
    """The oracle's demonstration of an episode: each goal's program's skill on its target, in turn."""
    for goal in spec.goals():
        named(goal.task.program).perform(skills, goal)


def achieved(spec: EpisodeSpec, outcome: Outcome, target: str, program: str, goal: int = 0) -> bool:
    """Did the rollout do `program` to `target` (the episode's ask, or a counterfactual's), as the
    task's goal number `goal`, and every other goal of the task as asked?"""
    return all(each(spec.asking(target, program, goal), outcome))


def each(spec: EpisodeSpec, outcome: Outcome) -> tuple[bool, ...]:
    """Whether the rollout reached each of the task's goals (one, or LIBERO-10's two or three)."""
    return tuple(named(g.task.program).judge(g, outcome, g.target) for g in spec.goals())


def succeeded(spec: EpisodeSpec, outcome: Outcome) -> bool:
    return all(each(spec, outcome))
