"""The furniture a place belongs to, typed: where on a fixture the place is (`Spot`), and the piece
it is a part of, each owning the thresholds LIBERO judges it by (as LIBERO's articulated objects
own their open and turn-on ranges): a cabinet's `Drawer`, the stove's `Knob`, the wine rack's
sloping `Shelf`, the microwave's `Door` and the `Inside` behind it, the desk caddy's narrow `Slot`. A kind (core/catalog.py)
carries them as typed fields, so the success predicates (core/success.py) and the skills
(oracle/furniture.py) read them by name (`Kind.part`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.rotations import X_AXIS, turned


@dataclass(frozen=True)
class Spot:
    """Where a place on a fixture is, which no scene moves: LIBERO's region site `site`, or the point
    `offset` in the frame of the body `body`, carried along as the body moves (a knob); `goal_name`
    is LIBERO's name of it in its goals where that is not the site's (the stove, for its knob)."""

    site: str = ""
    body: str = ""
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    goal_name: str = ""

    @property
    def anchor(self) -> str:
        """Where it is, as another simulator is asked to follow it: its site's name, or
        `<body>@<x>,<y>,<z>` (eval/sims/libero_env/server.py reads both)."""
        return self.site or f"{self.body}@{','.join(map(str, self.offset))}"


@dataclass(frozen=True)
class Drawer:
    """A cabinet drawer, its place the region site inside it: its handle bar `handle` from the site
    (the drawer's own frame, as `pull`, the way it slides out); `roll`, how far the hand taking it
    turns from closing straight up and down; `opening`, how far out from the closed drawer's site
    the cabinet's top ends and the inner face of its front lie (the uncovered part, open, is between);
    `press`, where a hand pushing it shut presses its front, from the site (the drawer's frame): the
    front's outer face below the site's height, beside the handle bar on the side away from the
    robot (in LIBERO-10's KITCHEN_SCENE4 a wine bottle stands before the other side); `drop`, how
    far over its floor a carried thing is let go (under other drawers, lower, the wrist met the
    handle bar of the drawer two above).
    Open once it slid `open_travel` out: LIBERO's cabinets, their joint below -0.14 m; closed once
    in past where it stands shut: their joint above 0 (it stops at 0.01 m)."""

    handle: tuple[float, float, float]
    opening: tuple[float, float]
    pull: tuple[float, float, float] = (0.0, -1.0, 0.0)
    roll: float = 0.0
    open_travel: float = 0.14
    press: tuple[float, float, float] = (0.075, -0.0892, -0.015)
    drop: float = 0.0

    def opened(self, start: tuple[float, ...], end: tuple[float, ...]) -> bool:
        return float(np.linalg.norm(np.subtract(end, start))) >= self.open_travel

    def closed(self, start: tuple[float, ...], end: tuple[float, ...], shut: tuple[float, ...]) -> bool:
        """Whether the drawer, its site `shut` where it stands shut, went from open at `start` to
        past `shut` at `end`, in along the way it had slid out (horizontally: a place's recorded
        height is where things rest in it)."""
        out = np.subtract(start, shut)[:2]
        travel = float(np.linalg.norm(out))
        return travel >= self.open_travel and float(np.subtract(end, shut)[:2] @ out) < 0.0


@dataclass(frozen=True)
class Knob:
    """A stove's knob, its place a point on it off its axis (its `Spot.offset`). On from `turn_on`
    radians: LIBERO's flat stove (it starts at 0 and turns one way only)."""

    turn_on: float = 0.5

    def on(self, start: tuple[float, ...], end: tuple[float, ...], radius: float) -> bool:
        """Whether the point `radius` from the axis went from `start` to `end` along an arc of
        `turn_on` or more: turned by an angle a, it moves 2 radius sin(a / 2), the chord."""
        chord = float(np.linalg.norm(np.subtract(end, start)))
        return chord >= 2 * radius * np.sin(self.turn_on / 2)


@dataclass(frozen=True)
class Door:
    """A door on an upright hinge (the microwave's), its place a point on it `Spot.offset` from the
    hinge, in the door's own frame, whose origin is on the hinge's axis (a swing carries the point
    round it). Open `open_turn` radians or more from shut; closed within `shut_turn` of shut:
    LIBERO's `Close` of the microwave, its hinge above -0.005 rad."""

    open_turn: float = 0.5
    shut_turn: float = 0.005

    def closed(self, start: tuple[float, ...], end: tuple[float, ...], shut: tuple[float, ...], radius: float) -> bool:
        """Whether the door, its point `shut` where it stands shut, went from open at `start` to shut
        at `end`: turned by an angle a, the point `radius` from the hinge is 2 radius sin(a / 2) away."""

        def turn(at: tuple[float, ...]) -> float:
            return 2.0 * float(np.arcsin(min(1.0, float(np.linalg.norm(np.subtract(at, shut))) / (2.0 * radius))))

        return turn(start) >= self.open_turn and turn(end) <= self.shut_turn


@dataclass(frozen=True)
class Inside:
    """The inside of a box behind a door (the microwave's), its place LIBERO's region site in it: a
    thing brought in is let down on its floor, `floor` below the site, `front` from the site toward
    its opening (`out`, the fixture's frame), where the hand holding it from above still clears the
    box's top; then the closed fingers push it in to the site (oracle/furniture.py `_push_inside`)."""

    floor: float
    front: float
    out: tuple[float, float, float] = (0.0, -1.0, 0.0)


@dataclass(frozen=True)
class Slot:
    """A narrow compartment a flat thing stands in (the desk caddy's back one, LIBERO-10's STUDY_SCENE1),
    its place LIBERO's region site in it. LIBERO's `In` wants the thing's origin over the region's box,
    its floor lowered 1 cm: a book standing on the compartment's floor misses it by 3.5 mm (its model's
    origin is 2.2 mm under its base), one resting against the wall before it, leaning 16–18°, is in by
    0.4–1.1 mm, in LIBERO's simulator as in ours. So a thing is let go leaning `lean` (rad) from upright, its
    top toward `toward` (the fixture's frame), its foot `foot` from the site away from that wall and
    `floor` below the site; the compartment's walls reach `rim` over the site (oracle/furniture.py
    `_lean_in`)."""

    floor: float
    foot: float
    lean: float
    rim: float
    toward: tuple[float, float, float] = (-1.0, 0.0, 0.0)


@dataclass(frozen=True)
class Shelf:
    """A sloping shelf (the wine rack's top), LIBERO's region site on it of half size `half`, turned
    `tilt` about its x. On it is a thing's origin in the site's box, up to `rise` over its face
    (LIBERO's `under`); a bottle is laid along it, its bottom `lay` from the site (along the site's
    x, and up the slope: oracle/skills.py `_lay`)."""

    half: tuple[float, float, float]
    tilt: float
    lay: tuple[float, float]
    rise: float = 0.10

    def turn(self) -> np.ndarray:
        """The site's turn against the fixture it is on: `tilt` about its x."""
        return turned(X_AXIS, self.tilt)

    def holds(self, delta: np.ndarray) -> bool:
        """Whether a thing `delta` from the site (in the site's frame, as LIBERO multiplies it) is on it."""
        half = np.asarray(self.half)
        return bool(np.all(np.abs(delta[:2]) < half[:2]) and half[2] < delta[2] < half[2] + self.rise)
