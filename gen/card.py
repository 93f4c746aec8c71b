"""The dataset card (README.md at the dataset root): what was generated, and how to redo it."""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import TYPE_CHECKING

from gen.config import GenConfig
from referents import Referent

if TYPE_CHECKING:
    from gen.run import Summary

FRONT_MATTER = """---
license: apache-2.0
task_categories:
- robotics
tags:
- LeRobot
- deconfounded
- referent-{referent}
configs:
- config_name: default
  data_files: data/*/*.parquet
---
"""


def command(cfg: GenConfig) -> str:
    parts = [f"referent={cfg.referent}", f"n={cfg.n}", f"seed={cfg.seed}", f"image_size={cfg.image_size}", f"fps={cfg.fps}"]
    if cfg.codec != "h264":
        parts.append(f"codec={cfg.codec}")
    if cfg.spec:
        parts.append(f"spec={cfg.spec}")
    if cfg.objects_per_scene is not None:
        parts.append(f"objects_per_scene={cfg.objects_per_scene}")
    return "python -m gen " + " ".join(parts)


def write(root: Path, referent: Referent, cfg: GenConfig, summary: Summary) -> None:
    rc = referent.config
    objects = "\n".join(f"| {c.key} | {c.kind} |" for c in rc.objects)
    templates = "\n".join(f"- `{t}`" for t in rc.templates)
    k = rc.objects_per_scene
    text = FRONT_MATTER.format(referent=referent.name) + f"""
# Deconfounded `{referent.name}` dataset

{summary.episodes} oracle-verified demonstrations ({summary.frames} frames at {cfg.fps} Hz) of a Panda
arm in MuJoCo, {k} objects per scene, in which the instruction is the only predictor of the target:
every object is the target equally often, in every slot, and appears as a distractor in every slot.
Format: LeRobot v3.0 (`observation.images.agentview`, `observation.images.wrist`,
`observation.state`, `action`); per-episode scene records and counterfactual instructions are in
`meta/scenes.parquet`.

## Objects

| object | model |
|---|---|
{objects}

## Instruction templates

{templates}

## Regenerate

```
{command(cfg)}
```

Oracle success before retries: {summary.episodes}/{summary.episodes + summary.failed_attempts}.
Targets per object: {dict(sorted(Counter(_targets(root)).items()))}.
"""
    (root / "README.md").write_text(text)


def _targets(root: Path) -> list[str]:
    from gen import scenes

    return list(scenes.read(root)["target"])
