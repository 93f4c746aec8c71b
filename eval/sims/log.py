"""The rollout log, one module both sides read: what a take writes per row (`Log`: the hand's and
the objects' positions per step, the movable containers' orientations, an error, the policy's
readouts, a simulator's own verdict) and its file's metadata, and how the scorer reads them back
(`read_logs`). rollouts.parquet holds one `Log.to_row()` per row.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import pandas as pd
import pyarrow.parquet as pq

SIM_SUCCESS = "sim_success"  # rollouts.parquet's column of a simulator's own verdict on the row's ask
POLICY_KEY, SIM_KEY = b"deconfound.policy", b"deconfound.sim"  # rollouts.parquet's metadata: who acted, and where
EXAM_KEY = b"deconfound.exam"  # ... on which exam (its digest, eval/scoring/baseline.py exam_digest); takes before it lack it
PREDICTION_KEY = b"deconfound.prediction_trained"  # ... and whether its predictions come from a trained head (true/false)
VERSIONS_KEY = b"deconfound.sim_versions"  # ... and the simulator's versions (JSON: {"mujoco", "robosuite", ...})
REQUIRED = ("row", "ee", "objects", "error")  # the columns every log has


class Positions(Protocol):
    """What a log records at each step: a simulator's hand, objects and containers."""

    def ee_pos(self) -> object: ...

    def positions(self) -> dict[str, tuple[float, ...]]: ...

    def turns(self) -> dict[str, tuple[float, ...]]: ...


class LogError(ValueError):
    """Rollout logs that do not match the exam; the message says how."""


@dataclass
class Log:
    row: int
    ee: list[list[float]] = field(default_factory=list)
    objects: dict[str, list[list[float]]] = field(default_factory=dict)
    turns: dict[str, list[list[float]]] = field(default_factory=dict)  # movable containers' orientations (w, x, y, z)
    error: str | None = None
    located: list[float] | None = None
    predicted: list[float] | None = None  # [column, row] in the agentview frame, with the first chunk
    sim_success: bool | None = None  # the simulator's own verdict on the row's ask (LIBERO's predicates), where it has one

    @property
    def steps(self) -> int:
        return max(len(self.ee) - 1, 0)

    def record(self, scene: Positions) -> None:
        self.ee.append([float(v) for v in scene.ee_pos()])
        for k, pos in scene.positions().items():
            self.objects.setdefault(k, []).append(list(pos))
        for k, quat in scene.turns().items():
            self.turns.setdefault(k, []).append(list(quat))

    def to_row(self) -> dict:
        verdict = {} if self.sim_success is None else {SIM_SUCCESS: self.sim_success}
        return {
            "row": self.row,
            "steps": self.steps,
            "ee": self.ee,
            "objects": json.dumps(self.objects),
            "turns": json.dumps(self.turns),
            "error": self.error,
            "located": self.located,
            "predicted": self.predicted,
            **verdict,
        }


def read_logs(path: Path) -> tuple[pd.DataFrame, str | None]:
    try:
        table = pq.read_table(path)
    except FileNotFoundError:
        raise LogError(f"no rollout logs at {path}") from None
    except Exception as exc:
        raise LogError(f"{path} is not a readable parquet file: {exc}") from None
    missing = set(REQUIRED) - set(table.column_names)
    if missing:
        raise LogError(f"{path} lacks columns {sorted(missing)}")
    meta = table.schema.metadata or {}
    logs = table.to_pandas()
    if SIM_KEY in meta:
        logs.attrs["sim"] = meta[SIM_KEY].decode()
    if EXAM_KEY in meta:
        logs.attrs["exam_digest"] = meta[EXAM_KEY].decode()
    if PREDICTION_KEY in meta:
        logs.attrs["prediction_trained"] = meta[PREDICTION_KEY] == b"true"
    if VERSIONS_KEY in meta:
        logs.attrs["sim_versions"] = json.loads(meta[VERSIONS_KEY])
    policy = meta.get(POLICY_KEY)
    return logs, policy.decode() if policy else None
