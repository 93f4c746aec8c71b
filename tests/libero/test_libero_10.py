"""LIBERO-10's scenes against LIBERO's own environment (`.venv-libero`, driven by
eval/sims/libero_env/reference.py), scene by scene as their worlds come (issue 53): the same
physics model, the fixtures where LIBERO stands them (within the 1 cm its placement draws anew at
each reset), and the same pictures at LIBERO-10's own initial states."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from core import libero, worlds
from core.spec import FAST, LOOKS
from eval.sims.libero_env.reference import model_arrays  # the same readout on both models
from helpers import PICTURE_STATES, initial_state_pictures, liberos_own, same_physics
from oracle.scene import scene_for

SUITE = "libero_10"
# world -> its LIBERO-10 task (the scene's first) and the objects it holds
SCENES = {
    "libero_10_kitchen_scene3": ("KITCHEN_SCENE3_turn_on_the_stove_and_put_the_moka_pot_on_it",
                                 (("chefmate_8_frypan", 1), ("moka_pot", 1))),
    "libero_10_kitchen_scene4": ("KITCHEN_SCENE4_put_the_black_bowl_in_the_bottom_drawer_of_the_cabinet_and_close_it",
                                 (("akita_black_bowl", 1), ("wine_bottle", 1))),
    "libero_10_kitchen_scene6": ("KITCHEN_SCENE6_put_the_yellow_and_white_mug_in_the_microwave_and_close_it",
                                 (("porcelain_mug", 1), ("white_yellow_mug", 1))),
    "libero_10_kitchen_scene8": ("KITCHEN_SCENE8_put_both_moka_pots_on_the_stove", (("moka_pot", 2),)),
    "libero_10_living_room": ("LIVING_ROOM_SCENE2_put_both_the_alphabet_soup_and_the_tomato_sauce_in_the_basket",
                              tuple((k, 1) for k in ("alphabet_soup", "cream_cheese", "tomato_sauce", "ketchup", "orange_juice",
                                                     "milk", "butter", "basket"))),
    "libero_10_study": ("STUDY_SCENE1_pick_up_the_book_and_place_it_in_the_back_compartment_of_the_caddy",
                        (("black_book", 1), ("white_yellow_mug", 1))),
}  # fmt: skip


@pytest.mark.reference
@pytest.mark.parametrize("world", SCENES)
def test_the_compiled_physics_is_liberos(world: str, tmp_path: Path) -> None:
    """Every body, joint, colliding geom, actuator and camera of the scene's LIBERO-10 task has its
    twin in ours, with the same values: the kitchen's table (its friction robosuite's 1, not the
    tabletop's 0.6) and mounted Panda, the living room's table and Panda on the floor, the stove,
    the moka pots, the frying pan, the groceries and the basket."""
    task, assets = SCENES[world]
    assert task in libero.tasks(SUITE)
    theirs = dict(np.load(liberos_own("model", {"suite": SUITE, "task": task}, tmp_path / "model.npz")))
    ours = model_arrays(scene_for(assets, "libero", world).model)
    compared = same_physics(theirs, ours, (f for f in libero.problem(SUITE, task).fixtures if not f.endswith("_table")))
    assert all(any(f":{kind}_1" in k for k in compared) for kind, _ in assets) and any("friction" in k for k in compared)
    for fixture in worlds.world(world).fixtures:  # at its region's centre: LIBERO draws it within 1 cm of it, turned as ours
        body = f"{fixture.name}_main"
        assert np.abs(theirs[f"body_pos:{body}"] - ours[f"body_pos:{body}"]).max() < 0.015, body
        assert np.allclose(theirs[f"body_quat:{body}"], ours[f"body_quat:{body}"], atol=1e-6), body


# the scene each world stands for, by the prefix of its tasks' names (the living room: four scenes)
PREFIXES = {
    "libero_10_kitchen_scene3": ("KITCHEN_SCENE3_",),
    "libero_10_kitchen_scene4": ("KITCHEN_SCENE4_",),
    "libero_10_kitchen_scene6": ("KITCHEN_SCENE6_",),
    "libero_10_kitchen_scene8": ("KITCHEN_SCENE8_",),
    "libero_10_living_room": ("LIVING_ROOM_SCENE",),
    "libero_10_study": ("STUDY_SCENE1_",),
}


# Things the fast look (core/spec.py LOOKS) cannot draw within helpers.OBJECT_BOUND: the stove's mirror
# top (22-29/255 agentview, its plate fitted in the kitchen too), the woven basket (24, as LIBERO-PRO's
# tests measure it) and the white mug's decimated mesh near the wrist camera (18). The full look draws
# every thing within it.
OWN_BOUNDS = {"flat_stove": 30.0, "basket": 28.0, "porcelain_mug": 19.0}
# Whole frames the fast look leaves over helpers.FRAME_BOUND (no shadows, no reflections): the living
# room's low camera sees the robot and the wall it shades (5.2/255; the full look 1.6), the second
# kitchen stove's mirror (4.15). Expected to fail until the fast look draws them.
FAST_SHORT = {"libero_10_living_room": "5.2/255 in the fast look", "libero_10_kitchen_scene8": "4.15/255 in the fast look"}


def _looks() -> list:
    return [
        pytest.param(world, look, marks=pytest.mark.xfail(strict=True, reason=FAST_SHORT[world]))
        if look == FAST and world in FAST_SHORT
        else (world, look)
        for world in PREFIXES
        for look in LOOKS
    ]


@pytest.mark.reference
@pytest.mark.parametrize(("world", "look"), _looks())
def test_the_same_pictures_at_liberos_own_initial_states(world: str, look: str, tmp_path: Path) -> None:
    """The first initial states (PICTURE_STATES) of each of the world's LIBERO-10 tasks, its objects
    loaded by their LIBERO names and the fixtures posed as LIBERO drew them: both cameras within
    helpers.FRAME_BOUND, every object and fixture within helpers.OBJECT_BOUND inside its own pixels
    (in the fast look, OWN_BOUNDS excepted), every object within 1 mm of where LIBERO puts it."""
    tasks = [i for i, name in enumerate(libero.tasks(SUITE)) if name.startswith(PREFIXES[world])]
    cases = [(t, s) for t in tasks for s in range(PICTURE_STATES)]
    pictures, farthest = initial_state_pictures(SUITE, cases, tmp_path, look, world=world)
    pictures.check(OWN_BOUNDS if look == FAST else None)
    assert farthest <= 0.001, f"an object stands {farthest * 1000:.2f} mm from where LIBERO puts it"
