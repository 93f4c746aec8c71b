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

from core import contact, programs, worlds
from core.exam import Exam, Switch, trial_rows
from core.spec import EpisodeSpec
from eval.scoring.score import CARRY_STAGES, score
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


def test_a_switch_row_counts_landings_from_its_switch_step() -> None:
    """A hand over the newly named object before the switch has not obeyed a name it was not yet
    given: a switch row is judged from its switch step (where it went before that counts for
    nothing), and lands where the hand last came within 5 cm: over the original when told, then
    on to the new one, obeyed; to the new one and back to the original, blind."""
    referent = registry.load("object", world="native")
    spec = plan(referent, 1, seed=0, setup=default_setup(referent), split="exam")[0]
    values = {a.id: a.value for a in referent.alternatives(spec)}
    rows = trial_rows(0, spec, values, [], 10, [-0.5, 0.0, 1.3], switches=(Switch(0, 2),))
    rows = [r | {"row": 0} for r in rows if r["face"] == "switch"]
    exam = Exam(Path("."), {"referent": "object", "trials": 1, "seed": 0}, pd.DataFrame(rows))
    new = rows[0]["target"]
    on_new = contact.grasp_point(worlds.kind(spec.object(new).kind, spec.setup.world), np.asarray(spec.object(new).pos)).tolist()
    objects = json.dumps({o.id: [list(o.pos)] * 4 for o in spec.objects})

    def switch_obeyed(*hand: list[float]) -> tuple[int, int]:
        """The switch row's (obeyed, blind) for a hand at `hand` at steps 1, 2, 3 (the switch comes at 2)."""
        logs = pd.DataFrame([{"row": 0, "ee": [rows[0]["initial_ee"], *hand], "objects": objects, "error": None}])
        faces = score(exam, logs, "hand")["faces"]
        return faces["switch_obeyed"]["k"], faces["switch_blind"]["k"]

    start, old = rows[0]["initial_ee"], spec.object(spec.target)
    on_old = contact.grasp_point(worlds.kind(old.kind, spec.setup.world), np.asarray(old.pos)).tolist()
    assert switch_obeyed(on_new, start, start) == (0, 0), "over it before the switch, gone after it"
    assert switch_obeyed(start, on_new, on_new) == (1, 0), "there from the switch on"
    assert switch_obeyed(on_old, on_old, on_new) == (1, 0), "over the original when told, then on to the new one"
    assert switch_obeyed(on_old, on_new, on_old) == (0, 1), "to the new one, then back to the original"


@pytest.mark.parametrize("world", registry.worlds_of("goal"))
def test_the_carry_probe_says_where_a_failed_carry_stopped(world: str) -> None:
    """A failed `put X on Y` is told apart by how far it got: the hand at another thing it could
    carry (X's name not read), at nothing, at X without lifting it (the grasp), or lifting X and
    not bringing it (the place). Each task and swap row's hand does one of these in turn; the probe
    counts each, per face."""
    exam, _ = _exam("goal", world)
    stages = CARRY_STAGES  # took_other, reached_none, not_lifted, lifted: each row's hand does the next
    logs, expected = _logs(exam, {}), {face: dict.fromkeys(stages, 0) for face in ("task", "obeyed_name")}
    faces = {"task": "task", "swap": "obeyed_name"}
    carries = [i for i, row in exam.trials.iterrows() if row["face"] in faces and programs.named(row["program"]).carries]
    for n, i in enumerate(carries):
        row, spec = exam.trials.loc[i], EpisodeSpec.from_json(exam.trials.at[i, "spec"])
        carried = spec.task.params["object"]
        others = [o for o in _graspable(spec) if worlds.kind(spec.object(o).kind, world).graspable()]
        stage = stages[n % len(stages)] if others else stages[1 + n % (len(stages) - 1)]
        objects = {k: np.array(v, float) for k, v in json.loads(logs.at[i, "objects"]).items()}
        goes_to = {"took_other": others[0] if others else None, "reached_none": None}.get(stage, carried)
        if stage == "lifted":
            objects[carried][1, 2] += 0.1
        if goes_to is not None:
            kind = worlds.kind(spec.object(goes_to).kind, world)
            logs.at[i, "ee"] = [logs.at[i, "ee"][0], contact.grasp_point(kind, objects[goes_to][1]).tolist()]
        logs.at[i, "objects"] = json.dumps({k: v.tolist() for k, v in objects.items()})
        expected[faces[row["face"]]][stage] += 1
    report = score(exam, logs, "stages")
    assert expected["task"] != dict.fromkeys(stages, 0) and report["carry_probe"] == expected
