"""The objects a native scene can hold, with the geometry the planner needs before any simulation.

Each kind names one of robosuite's object models (built in oracle/scene.py); other worlds
declare their own (core/worlds/), looked up by `core.worlds.kind(name, world)`. Extents are
stored here (measured from the compiled meshes; tests check them against the model) so that
planning stays pure: no simulator is imported to know where an object rests or how tall it is.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, TypeVar

from core.furniture import Door, Drawer, Inside, Knob, Shelf, Slot, Spot

Piece = TypeVar("Piece", Spot, Drawer, Knob, Shelf, Door, Inside, Slot)

# Named colors an instruction may use, as RGBA.
COLORS: dict[str, tuple[float, float, float, float]] = {
    "red": (0.85, 0.10, 0.10, 1.0),
    "green": (0.10, 0.65, 0.15, 1.0),
    "blue": (0.10, 0.25, 0.85, 1.0),
    "yellow": (0.95, 0.85, 0.10, 1.0),
    "purple": (0.55, 0.15, 0.70, 1.0),
    "orange": (0.95, 0.50, 0.05, 1.0),
    "white": (0.92, 0.92, 0.92, 1.0),
    "black": (0.08, 0.08, 0.08, 1.0),
}


GRIPPER_SPAN = 0.08  # the Panda's fingers open this far apart: nothing wider across its grasp axis can be picked
SITE = "site"  # the model of a place on a fixture (core/libero.py): somewhere things go, nothing to pick up
RIM_DEPTH = 0.02  # measured from LIBERO-Spatial's 50 first states: 10 mm let the wall slip in 4, 20 mm in none


@dataclass(frozen=True)
class Kind:
    """A buildable object.

    `model` is the robosuite class in `robosuite.models.objects` and `params` its constructor
    arguments (`libero`: LIBERO's model file `params["xml"]`, its drawn mesh cut to `params["faces"]`
    triangles; `site`: a place on a fixture, which no scene moves, where `spot` says, and a part of
    the furniture where `drawer`, `knob` or `shelf` says which: core/furniture.py); `size` is
    the extent (x, y, z) in the object's resting frame (its model frame turned by `quat`),
    `bottom` the height of its lowest point below the body origin, and `grasp_axis` the
    resting-frame axis ("x" or "y") the fingers close along: the narrower one. Colorable kinds
    take their RGBA from the object's `color` attribute. Destinations (plate, basket) are placed
    on, not grasped; `inner` is the half-width of the area an object must land in, and a
    container's `contain` box (centre offset from the body origin, half size) is the volume an
    object's origin must be in to be in it (LIBERO's `In`). `contain_quat` is the orientation, at
    rest, of LIBERO's region site that box stands for: LIBERO's `in_box` takes a turned container's
    box along the world's axes with extents |R half| (R the site's orientation, half its size), so
    a basket knocked askew by a dropped grocery holds what LIBERO says it holds (core/success.py).
    """

    name: str
    model: str
    size: tuple[float, float, float]
    bottom: float
    grasp_axis: str = "y"
    colorable: bool = False
    params: dict[str, Any] = field(default_factory=dict)
    inner: float = 0.0
    quat: tuple[float, ...] = (1.0, 0.0, 0.0, 0.0)  # resting orientation (w, x, y, z) before the object's yaw
    contain: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None  # (centre offset, half size)
    contain_quat: tuple[float, ...] = (1.0, 0.0, 0.0, 0.0)  # LIBERO's region site, at rest (before the object's yaw)
    rim: float = 0.0  # > 0: a bowl, picked by its wall, this far from its centre
    # where the hand takes a thing too wide to take whole (a moka pot's handle): from its origin, as
    # it rests (before its yaw); the fingers close across it along `grasp_axis`
    handle: tuple[float, float, float] | None = None
    variant_of: str = ""  # the kind this one recolours or resizes (LIBERO-PRO's copies): what it is called, and stands for
    called: str = ""  # what a person calls it, where that is not its name's words (`yellow mug`)
    neck: bool = False  # held by a narrow neck (a bottle): it swings, so it is carried gently (oracle/motion.py GENTLE)
    # where two things brought to it stand (LIBERO-10's "put both ..."): this far (x, y) from its centre,
    # the first one way, the second the other (core/libero_goals.py); None: both at its centre
    side_by_side: tuple[float, float] | None = None
    spot: Spot | None = None  # a place on a fixture: where it is
    drawer: Drawer | None = None
    knob: Knob | None = None
    shelf: Shelf | None = None
    door: Door | None = None
    inside: Inside | None = None
    slot: Slot | None = None

    @property
    def is_site(self) -> bool:
        """A place on a fixture (a stove's burner), which no scene moves: an object of the scene only
        as somewhere to put things."""
        return self.model == SITE

    @property
    def walled(self) -> bool:
        """A container standing among the objects (LIBERO's basket), its walls over what it holds:
        a thing is let down inside it, not dropped from over its rim."""
        return self.contain is not None and not self.is_site

    def part(self, piece: type[Piece]) -> Piece:
        """This kind's `piece` (its Spot, Drawer, Knob, Shelf, Door, Inside or Slot), or a ValueError saying it has none."""
        found = {
            Spot: self.spot,
            Drawer: self.drawer,
            Knob: self.knob,
            Shelf: self.shelf,
            Door: self.door,
            Inside: self.inside,
            Slot: self.slot,
        }[piece]
        if found is None:
            raise ValueError(f"{self.name} has no {piece.__name__.lower()}")
        return found

    def beside(self, nth: int) -> list[float] | None:
        """Where the `nth` (0 or 1) of two things brought to it stands, from its centre (`side_by_side`:
        the first one way, the second the other); None: at its centre."""
        if self.side_by_side is None:
            return None
        sign = 1.0 if nth == 0 else -1.0
        return [sign * v for v in self.side_by_side]

    @property
    def anchor(self) -> str:
        """Where a place on a fixture is, as another simulator is asked to follow it (`Spot.anchor`)."""
        return self.part(Spot).anchor

    @property
    def noun(self) -> str:
        return self.called or self.name.replace("_", " ")

    @property
    def height(self) -> float:
        return self.size[2]

    def rest_z(self, surface_z: float) -> float:
        """Body-origin height when the object rests on a surface at `surface_z`."""
        return surface_z + self.bottom

    def graspable(self) -> bool:
        """Whether the open fingers fit across it (a bowl, taken by its wall, or a thing by its handle, always)."""
        return bool(self.rim) or self.handle is not None or self.size[0 if self.grasp_axis == "x" else 1] < GRIPPER_SPAN

    def grasp_depth(self) -> float:
        """How far below the top the fingers close: near the top for tall objects, and just
        below a bowl's rim, so the inner finger stays clear of its floor."""
        return min(RIM_DEPTH if self.rim else 0.03, self.height / 2)


def _cube(side: float) -> dict[str, Any]:
    return {"size": [side / 2] * 3}


KINDS: dict[str, Kind] = {
    k.name: k
    for k in (
        Kind("milk", "MilkObject", (0.040, 0.040, 0.144), 0.061),
        Kind("can", "CanObject", (0.050, 0.050, 0.080), 0.040),
        Kind("bottle", "BottleObject", (0.055, 0.059, 0.160), 0.065, grasp_axis="x"),
        Kind("bread", "BreadObject", (0.048, 0.040, 0.048), 0.023),
        Kind("cereal", "CerealObject", (0.100, 0.030, 0.150), 0.075),
        Kind("lemon", "LemonObject", (0.068, 0.040, 0.040), 0.020),
        Kind("block", "BoxObject", (0.040, 0.040, 0.040), 0.020, colorable=True, params=_cube(0.04)),
        Kind("block_small", "BoxObject", (0.030, 0.030, 0.030), 0.015, colorable=True, params=_cube(0.03)),
        Kind("block_large", "BoxObject", (0.056, 0.056, 0.056), 0.028, colorable=True, params=_cube(0.056)),
        Kind("cylinder", "CylinderObject", (0.040, 0.040, 0.060), 0.030, colorable=True, params={"size": [0.02, 0.03]}),
        Kind("ball", "BallObject", (0.056, 0.056, 0.056), 0.028, colorable=True, params={"size": [0.028]}),
        Kind(
            "plate",
            "CylinderObject",
            (0.150, 0.150, 0.012),
            0.006,
            params={"size": [0.075, 0.006], "rgba": [0.55, 0.7, 0.9, 1]},
            inner=0.06,
        ),
        Kind(
            "basket",
            "Bin",
            (0.150, 0.150, 0.060),
            0.030,
            params={
                "bin_size": [0.15, 0.15, 0.06],
                "wall_thickness": 0.008,
                "transparent_walls": False,
                "use_texture": False,
                "rgba": [0.55, 0.35, 0.15, 1],
            },
            inner=0.055,
        ),
    )
}
