"""The dataset card (README.md at the dataset root): what was deconfounded, the audit that
shows it, and how to regenerate the data."""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING

from core import __version__
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


def spec_hash(referent: Referent) -> str:
    """Content hash of the resolved referent spec (recorded in the card and generation.json)."""
    return hashlib.sha256(json.dumps(asdict(referent.config), sort_keys=True, default=str).encode()).hexdigest()[:16]


def provenance(referent: Referent, cfg: GenConfig) -> str:
    return (
        f"| generator | deconfound {__version__} |\n| referent spec hash | `{spec_hash(referent)}` |\n| seed | {cfg.seed} |\n"
        f"| simulator | mujoco {metadata.version('mujoco')}, robosuite {metadata.version('robosuite')} |"
    )


def command(cfg: GenConfig) -> str:
    """The `python -m gen ...` line that regenerates a dataset made with `cfg`."""
    parts = [f"referent={cfg.referent}", f"n={cfg.n}", f"seed={cfg.seed}", f"image_size={cfg.image_size}", f"fps={cfg.fps}"]
    for name in ("codec", "spec", "objects_per_scene", "confound", "split"):
        value = getattr(cfg, name)
        if value is not None and value != GenConfig.__dataclass_fields__[name].default:
            parts.append(f"{name}={value}")
    for name in ("holdout", "distractor_only", "targets"):
        if getattr(cfg, name):
            parts.append(f"'{name}=[{','.join(repr(v) for v in getattr(cfg, name))}]'")
    if cfg.plan_only:
        parts.append("plan_only=true")
    return "python -m gen " + " ".join(parts)


def audit_tables(report: dict) -> str:
    """The audit as markdown: one row per variable, then the role balance per value."""
    lines = [
        f"**Verdict: {report['verdict']}** ({report['episodes']} episodes, chance {report['chance']:.0%}; {report['method']}).",
        "",
        "| variable | held-out accuracy | 95% CI | chance | leak |",
        "|---|---|---|---|---|",
    ]
    for v in report["variables"]:
        flag = ("yes (requested)" if v["expected"] else "**YES**") if v["leak"] else "no"
        lines.append(
            f"| {v['variable']} | {v['rate']:.1%} ({v['k']}/{v['n']}) "
            f"| {v['ci'][0]:.1%}–{v['ci'][1]:.1%} | {v['chance']:.0%} | {flag} |"
        )
    lines += ["", "| value | as target | as distractor | slots as target | slots as distractor |", "|---|---|---|---|---|"]
    for value, roles in report["balance"].items():
        t, d = roles["target"], roles["distractor"]
        lines.append(f"| {value} | {sum(t.values())} | {sum(d.values())} | {len(t)} | {len(d)} |")
    return "\n".join(lines)


def write(root: Path, referent: Referent, cfg: GenConfig, summary: Summary, report: dict) -> None:
    rc = referent.config
    objects = "\n".join(f"| {c.key} | {c.kind} | {'' if c.targetable else 'distractor only'} |" for c in rc.objects)
    templates = "\n".join(f"- `{t}`" for t in rc.templates)
    vocabulary = ""
    if rc.holdout or rc.distractor_only or rc.targets:
        vocabulary = (
            f"\nVocabulary control: held out entirely: {', '.join(rc.holdout) or 'none'}; "
            f"distractor only (never the target): {', '.join(rc.distractor_only) or 'none'}; "
            f"only these may be the target: {', '.join(rc.targets) or 'all'}.\n"
        )
    if rc.confound:
        vocabulary += (
            f"\n**Deliberately confounded (`confound={rc.confound}`)**: "
            "made to reproduce instruction blindness, not to train on.\n"
        )
    contents = (
        f"A plan of {summary.episodes} episodes (`plan_only=true`: scene records and audit only, nothing simulated)."
        if summary.plan_only
        else f"{summary.episodes} oracle-verified demonstrations ({summary.frames} frames at {cfg.fps} Hz) of a Panda arm in "
        f"MuJoCo. Format: LeRobot v3.0 (`observation.images.agentview`, `observation.images.wrist`, "
        f"`observation.state`, `action`). Oracle success before retries: "
        f"{summary.episodes}/{summary.episodes + summary.failed_attempts}."
    )
    text = (
        FRONT_MATTER.format(referent=referent.name)
        + f"""
# Deconfounded `{referent.name}` dataset

{contents}

The instruction names the target by its **{rc.naming}**; every value of it is the target and a
distractor across slots, with {rc.objects_per_scene} objects per scene, all in view. Per-episode
scene records and the one-word counterfactual instructions are in `meta/scenes.parquet`; the
confound audit is in `meta/audit.json`.
{vocabulary}
## Confound audit

{audit_tables(report)}

## Objects

| object | model | |
|---|---|---|
{objects}

## Instruction templates

{templates}

## Provenance

| | |
|---|---|
{provenance(referent, cfg)}

## Regenerate, and take the matching exam

```
{command(cfg)}
{exam_command(cfg)}
python -m eval policy=<your policy> exam=datasets/{referent.name}-exam
```
"""
    )
    (root / "README.md").write_text(text)


def exam_command(cfg: GenConfig) -> str:
    """The held-out exam for a dataset: same referent and options, exam split, another seed."""
    dropped = ("n", "seed", "plan_only", "split", "confound", "holdout", "distractor_only")
    kept = [p for p in command(cfg).split(" ") if p.split("=")[0].lstrip("'") not in dropped]
    return " ".join([*kept, "n=200", f"seed={cfg.seed + 1}", "split=exam"])


def write_exam(root: Path, referent: Referent, cfg: GenConfig, summary: Summary, report: dict) -> None:
    """The exam's card: what it tests, its faces, how to take it, and its plan's audit."""
    from core.exam import FACES

    faces = "\n".join(f"| `{name}` | {text} |" for name, text in FACES.items())
    text = (
        FRONT_MATTER.format(referent=referent.name).replace("  data_files: data/*/*.parquet", "  data_files: trials.parquet")
        + f"""
# Counterfactual exam: `{referent.name}`

{summary.episodes} oracle-solvable trials on the held-out `exam` random stream (scene hashes never
occur in a training split). Each trial holds the pixels, scene and robot pose fixed and changes
one word. Files: `exam.json` (format, scoring parameters, object geometry, referent spec, audit)
and `trials.parquet` (one row per rollout); the format is documented in `exam.json` and in the
generator's `core/exam.py`.

| face | meaning |
|---|---|
{faces}

Take it in our simulator: `python -m eval policy=<oracle|position|nothing|random|remote:HOST:PORT|ckpt:PATH>
exam=<this folder>`; or in your own code, with `gymnasium.make("eval.env:deconfound/Exam-v0", exam=..., row=i)` and score your
logs with `python -m eval.score exam=<this folder> logs=<rollouts.parquet>`.

## Confound audit of the plan

{audit_tables(report)}

## Provenance

| | |
|---|---|
{provenance(referent, cfg)}

## Regenerate

```
{command(cfg)}
```
"""
    )
    (root / "README.md").write_text(text)
