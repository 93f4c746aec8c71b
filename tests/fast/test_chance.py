"""Chance is one over what a hand can land on, for every type in every world that carries it: the
row's alternatives and every other object of the scene the program could act on (a negation
scene's fourth grocery, a relation's anchor), never what the program carries things into or a
place on furniture; a landing on such an object is a distractor's. Scored on plans, without a
simulator: each rollout's hand goes straight to one object and stays."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from core import contact, worlds
from core.exam import Exam, trial_rows
from core.spec import EpisodeSpec
from eval.scoring.score import score
from gen.planning.plan import default_setup, plan
from referents import registry

CASES = [(name, world) for name in registry.available() for world in registry.worlds_of(name)]


def _exam(name: str, world: str) -> tuple[Exam, list[EpisodeSpec]]:
    referent = registry.load(name, world=world)
    specs = plan(referent, 3, seed=0, setup=default_setup(referent), split="exam")
    rows: list[dict] = []
    for trial, spec in enumerate(specs):
        values = {a.id: a.value for a in referent.alternatives(spec)}
        rows += trial_rows(trial, spec, values, [], 10, [-0.5, 0.0, 1.3])
    for i, r in enumerate(rows):
        r["row"] = i
    return Exam(Path("."), {"referent": name, "trials": len(specs), "seed": 0}, pd.DataFrame(rows)), specs


def _graspable(spec: EpisodeSpec) -> list[str]:
    params, world = spec.task.params, spec.setup.world
    carried = {params.get("destination"), params.get("object")}
    return [o.id for o in spec.objects if o.id not in carried and not worlds.kind(o.kind, world).is_site]


def _logs(exam: Exam, land_on: dict[int, str]) -> pd.DataFrame:
    out = []
    for _, row in exam.trials.iterrows():
        spec = EpisodeSpec.from_json(row["spec"])
        objects = {o.id: np.array([o.pos, o.pos], float) for o in spec.objects}
        ee = [list(row["initial_ee"]), list(row["initial_ee"])]
        target = land_on.get(int(row["row"]))
        if target is not None:
            ee[1] = contact.grasp_point(worlds.kind(spec.object(target).kind, spec.setup.world), objects[target][1]).tolist()
        logged = json.dumps({k: v.tolist() for k, v in objects.items()})
        out.append({"row": int(row["row"]), "ee": ee, "objects": logged, "error": None})
    return pd.DataFrame(out)


@pytest.mark.parametrize("name,world", CASES, ids=[f"{n}@{w}" for n, w in CASES])
def test_chance_is_one_over_what_the_hand_can_land_on(name: str, world: str) -> None:
    exam, specs = _exam(name, world)
    swaps = exam.trials[exam.trials.face == "swap"]
    report = score(exam, _logs(exam, {}), "nothing")
    programs = {row["program"] for _, row in swaps.iterrows()} | {row["original_program"] for _, row in swaps.iterrows()}
    if "place" in programs:  # where something is put: the destinations the instruction chooses among
        expected = [1 / len(json.loads(row["alternatives"])) for _, row in swaps.iterrows()]
    else:  # every object the program could act on, and a second program on the named one (verb)
        expected = [1 / (len(_graspable(EpisodeSpec.from_json(row["spec"]))) + len(programs) - 1) for _, row in swaps.iterrows()]
    assert report["faces"]["obeyed_name"]["chance"] == pytest.approx(float(np.mean(expected)), abs=1e-4)


@pytest.mark.parametrize("world", registry.worlds_of("negation"))
def test_a_landing_on_the_object_no_swap_names_is_a_distractors(world: str) -> None:
    """Negation's fourth object (the other shape in the other color) is never an alternative: a hand
    that goes there went to a distractor, and the report's chance counts it."""
    exam, _ = _exam("negation", world)
    land_on, asked = {}, exam.trials[exam.trials.face == "swap"]
    for _, row in asked.iterrows():
        spec = EpisodeSpec.from_json(row["spec"])
        named = {a["target"] for a in json.loads(row["alternatives"])}
        land_on[int(row["row"])] = next(i for i in _graspable(spec) if i not in named)
    report = score(exam, _logs(exam, land_on), "fourth")
    assert report["faces"]["obeyed_name"]["k"] == 0 and report["faces"]["true_target"]["k"] == 0
    assert report["reach_probe"]["obeyed_name"]["went_distractor"] == len(asked)
    assert report["faces"]["obeyed_name"]["chance"] == pytest.approx(0.25)
