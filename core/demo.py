"""What a demonstration is written in: the skill API, as referents see it.

A referent type's `demo(skills, spec)` is a few lines over these skills (ManiSkill's
motion-planning solutions read the same way); the oracle (oracle/skills.py) implements them on
a simulated scene. Declaring the API here keeps referents free of any simulator import.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from core.spec import EpisodeSpec


class Skills(Protocol):
    def grasp(self, object_id: str, onto: str | None = None) -> None:
        """Come down on the object from above and close the fingers on it (across the slope of a
        sloping shelf it will be laid `onto`)."""

    def lift(self, height: float = 0.15) -> None:
        """Raise the hand (and whatever it holds) straight up by `height` metres."""

    def place(self, destination_id: str, at: tuple[float, float] | None = None) -> None:
        """Carry the held object over the destination, lower it onto it (lay it along a sloping
        shelf), release; `at`: where on it, from its centre (two things on one place)."""

    def push(self, object_id: str) -> None:
        """Slide the object along the table, away from the robot."""

    def push_to(self, object_id: str, region_id: str) -> None:
        """Slide a dish along the table into a region (LIBERO-Goal's "push the plate to ...")."""

    def turn_on(self, knob_id: str) -> None:
        """Take a knob and turn it the way it turns on."""

    def pull_open(self, drawer_id: str, travel: float = ...) -> None:
        """Take a drawer's handle and pull the drawer `travel` out (nothing where it is out that far)."""

    def put_in(self, object_id: str, place_id: str) -> None:
        """Put the object inside a place (a drawer, opened part way; the microwave's inside)."""

    def shut(self, place_id: str) -> None:
        """Shut a drawer, pushed in, or a door, swung round its hinge."""


DemoScript = Callable[[Skills, EpisodeSpec], None]  # a demonstration, written over the skills: `demo(skills, spec)`
