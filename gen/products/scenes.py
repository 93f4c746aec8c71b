"""meta/scenes.parquet: one row per episode with everything needed to rebuild its scene.

Columns: episode_index (int), referent, instruction, target (an object id), scene (JSON
`{"objects": [{"id", "kind", "name", "slot", "pos", "yaw", "attributes"}]}`), counterfactuals
(JSON list of `{"instruction", "target", "changed"}`), spec (the full episode spec as JSON),
spec_hash, scene_hash, failed_attempts (oracle attempts before the recorded one),
initial_state (MuJoCo mjSTATE_INTEGRATION vector at frame 0) and outcome (JSON: every object's
start and end position, the final end-effector position). A plan (`plan_only=true`) leaves the
last three empty. A dataset mixing referent types (gen/planning/mix.py) also names each episode's world
(`world`, after `referent`): its types may be laid out in different worlds. A dataset whose
episodes change course (`switched=`) also has `switch` (after `target`): for a switched episode
JSON `{"step", "instruction", "target", "program"}`, the first frame shown the second instruction
(empty in a plan) and what that asks; null for the others. `instruction` and `target` are the first.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from core import parquet
from core.products import SCENES_PATH
from core.spec import EpisodeSpec

if TYPE_CHECKING:
    from core.success import Outcome
    from gen.products.produce import Produced


def row(
    episode_index: int, spec: EpisodeSpec, produced: Produced | None = None, mixed: bool = False, switched: bool = False
) -> dict:
    """A scene record; without `produced` (a plan), the simulation columns are empty."""
    world = {"world": spec.setup.world} if mixed else {}
    switch = {"switch": _switch(spec, produced)} if switched else {}
    return {
        "episode_index": episode_index,
        "referent": spec.referent,
        **world,
        "instruction": spec.instruction,
        "target": spec.target,
        **switch,
        "scene": json.dumps(spec.scene_record()),
        "counterfactuals": json.dumps([c.to_dict() for c in spec.counterfactuals]),
        "spec": spec.to_json(),
        "spec_hash": spec.hash,
        "scene_hash": spec.scene_hash,
        "failed_attempts": len(produced.failures) if produced else None,
        "initial_state": produced.initial_state.astype(np.float64).tolist() if produced else None,
        "outcome": json.dumps(_positions(produced.outcome)) if produced else None,
    }


def _switch(spec: EpisodeSpec, produced: Produced | None) -> str | None:
    """Where a switched episode's instruction changes, and what it asks from there on."""
    if spec.switch is None:
        return None
    then = spec.after_switch()
    step = produced.episode.switch[0] if produced is not None and produced.episode.switch else None
    return json.dumps({"step": step, "instruction": then.instruction, "target": then.target, "program": then.task.program})


def _positions(outcome: Outcome) -> dict:
    """The outcome's positions, as the record has always held them: a basket's end orientation
    (`turns`), which the verdict also read, is left out."""
    return {k: v for k, v in asdict(outcome).items() if k != "turns"}


def write(root: Path, rows: list[dict]) -> None:
    pq.write_table(pa.Table.from_pylist(rows), root / SCENES_PATH)


def read(root: Path) -> pd.DataFrame:
    return parquet.read(root / SCENES_PATH)


def specs(root: Path) -> list[EpisodeSpec]:
    return [EpisodeSpec.from_json(s) for s in read(root)["spec"]]
