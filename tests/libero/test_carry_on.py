"""A switch after the grasp: in LIBERO-Goal's scene, "… on the plate" changed to "… on the stove"
for the same held object. The oracle changes course once the object is carried, not at the
approach (where such a switch changes nothing the hand does), and carries it on to the new place
without putting it down."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from core import programs
from core.exam import SWITCH_DISTANCE
from gen.planning.plan import default_setup, plan
from oracle.episode import CARRIED, approach_step, demonstrate
from oracle.ik import ArmIK
from oracle.motion import CLOSED
from oracle.scene import scene_for
from referents import registry


def test_a_switch_that_keeps_the_object_carries_it_on() -> None:
    referent = registry.load("libero_goal")
    setup = default_setup(referent)
    scene = scene_for(referent.assets(), setup.profile, setup.world)
    ik = ArmIK(np.asarray(setup.robot_home), setup.world)
    spec, other = next(
        (spec, i)
        for spec in plan(referent, 8, 5, setup)
        if spec.task.program == "place"
        for i, cf in enumerate(spec.counterfactuals)
        if spec.choice(cf) == (cf.target, "place") and cf.target != spec.target
    )
    switched = replace(spec, switch=other)
    demo = demonstrate(scene, ik, switched, referent.demo)
    assert demo.success, demo.failure
    held = spec.task.params["object"]
    first = demonstrate(scene, ik, spec, referent.demo)
    assert demo.switch_step > approach_step(scene, first, SWITCH_DISTANCE)  # after the grasp, not at the approach
    assert np.array_equal(demo.actions[: demo.switch_step], first.actions[: demo.switch_step])
    heights = []
    for state in demo.states[demo.switch_step :]:
        scene.set_physics_state(state)
        heights.append(scene.object_pos(held)[2])
    scene.set_physics_state(first.states[0])
    resting = scene.object_pos(held)[2]
    then = programs.named("place")
    assert then.moved(switched.after_switch(), switched.after_switch().target) == held
    # from the switch until the hand lets go, the object never comes back down to where it stood
    closed = demo.actions[demo.switch_step :, -1] == CLOSED
    let_go = int(np.argmin(closed)) if not closed.all() else len(closed)
    assert let_go > 0 and min(heights[:let_go]) > resting + CARRIED / 2, (resting, min(heights[:let_go]))
