"""The dataset card (README.md at the dataset root): what was deconfounded, the audit that
shows it, and how to regenerate the data."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from core.products import CARD_PATH, PREVIEW_PATH
from core.profiles import ACTION_KEY, NATIVE, STATE_KEY, Profile
from gen.products.provenance import Provenance
from referents.registry import Referent
from referents.schema import ReferentConfig

FRONT_MATTER = """---
license: apache-2.0
task_categories:
- robotics
tags:
- LeRobot
- {kind}
- referent-{referent}
configs:
- config_name: default
  data_files: data/*/*.parquet
---
"""


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


def dataset_contents(episodes: int, frames: int, failed_attempts: int, fps: int, features: Profile) -> str:
    keys = ", ".join(f"`{k}`" for k in (*features.image_keys, STATE_KEY, ACTION_KEY))
    text = (
        f"{episodes} oracle-verified demonstrations ({frames} frames at {fps} Hz) of a Panda arm in "
        f"MuJoCo. Format: LeRobot v3.0 ({keys}). Oracle success before retries: "
        f"{episodes}/{episodes + failed_attempts}."
    )
    if features.name != NATIVE.name:
        text += f"\n\n{profile_note(features, fps)}"
    return text


def profile_note(features: Profile, fps: int) -> str:
    """What the features mean in a non-native profile, said where a fine-tuner looks first."""
    cams = ", ".join(f"`{features.image_key(c)}` ({model})" for c, model in features.cameras.items())
    mirrored = ", stored upright and mirrored left to right as in lerobot's LIBERO datasets" if features.mirrored else ""
    return (
        f"**Profile `{features.name}`**: recorded at **{fps} Hz** (control and video). Cameras {cams}{mirrored}. "
        f"`{STATE_KEY}` ({features.state_size}): {', '.join(features.state_names)}. "
        f"`{ACTION_KEY}` ({features.action_size}): {features.action_meaning}."
    )


def plan_contents(episodes: int) -> str:
    return f"A plan of {episodes} episodes (`plan_only=true`: scene records and audit only, nothing simulated)."


def write(root: Path, audited: Sequence[tuple[Referent, dict]], provenance: Provenance, contents: str) -> None:
    """The card of a dataset or a plan, given each referent type with its audit (several: a mix,
    gen/planning/mix.py); `contents` says which and how much. A contact sheet (`preview.png`) beside it is
    shown at the top."""
    sheet = (
        f"\n![The first frame of the first episodes, with their instructions]({PREVIEW_PATH})\n"
        if (root / PREVIEW_PATH).is_file()
        else ""
    )
    text = _one(*audited[0], provenance, contents, sheet) if len(audited) == 1 else _mix(audited, provenance, contents, sheet)
    (root / CARD_PATH).write_text(text)


def _vocabulary(rc: ReferentConfig) -> str:
    """What the options held out, kept from the target or confounded on purpose."""
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
    return vocabulary


def _objects(rc: ReferentConfig) -> str:
    return "\n".join(f"| {c.key} | {c.kind} | {'' if c.targetable else 'distractor only'} |" for c in rc.objects)


def _templates(rc: ReferentConfig) -> str:
    return "\n".join(f"- `{t}`" for t in rc.templates)


def _kind(referents: Sequence[Referent]) -> str:
    """What the card calls the data: `confounded` where a type was laid out with a shortcut on
    purpose (`confound=`, the twin a deconfounded set is compared with), else `deconfounded`."""
    return "confounded" if any(r.config.confound for r in referents) else "deconfounded"


def _one(referent: Referent, report: dict, provenance: Provenance, contents: str, sheet: str) -> str:
    rc = referent.config
    kind = _kind([referent])
    return (
        FRONT_MATTER.format(referent=referent.name, kind=kind)
        + f"""
# {kind.capitalize()} `{referent.name}` dataset

{contents}
{sheet}
The instruction names the target by its **{rc.naming}**; every value of it is the target and a
distractor across slots, with {rc.objects_per_scene} objects per scene, all in view. Per-episode
scene records and the one-word counterfactual instructions are in `meta/scenes.parquet`; the
confound audit is in `meta/audit.json`.
{_vocabulary(rc)}
## Confound audit

{audit_tables(report)}

## Objects

| object | model | |
|---|---|---|
{_objects(rc)}

## Instruction templates

{_templates(rc)}

## Provenance

| | |
|---|---|
{provenance.table()}

## Regenerate, and take the matching exam

```
{provenance.command()}
{provenance.exam_command()}
python -m eval policy=<your policy> exam=datasets/{referent.name}-exam
```
"""
    )


def _mix(audited: Sequence[tuple[Referent, dict]], provenance: Provenance, contents: str, sheet: str) -> str:
    """A mix's card: what the types share, then each type as its own card would say it."""
    names = [referent.label for referent, _ in audited]
    sections = "".join(
        f"""
## `{referent.label}` (world {referent.config.world})

The instruction names the target by its **{referent.config.naming}**; every value of it is the target and a
distractor across slots, with {referent.config.objects_per_scene} objects per scene, all in view.
{_vocabulary(referent.config)}
### Confound audit

{audit_tables(report)}

### Objects

| object | model | |
|---|---|---|
{_objects(referent.config)}

### Instruction templates

{_templates(referent.config)}
"""
        for referent, report in audited
    )
    exams = "\n".join(
        f"python -m eval policy=<your policy> exam=datasets/{referent.name}"
        f"{'' if referent.label == referent.name else '-' + referent.config.world}-exam"
        for referent, _ in audited
    )
    kind = _kind([referent for referent, _ in audited])
    made = "deconfounded" if kind == "deconfounded" else "laid out as its `confound` says"
    return (
        FRONT_MATTER.format(referent="\n- referent-".join(dict.fromkeys(referent.name for referent, _ in audited)), kind=kind)
        + f"""
# {kind.capitalize()} dataset of {len(names)} referent types: {", ".join(f"`{name}`" for name in names)}

{contents}
{sheet}
{provenance.config.n // len(names)} episodes of each type, taking turns in this order (episode i is of
the type at place i mod {len(names)}), so every prefix of the dataset holds them equally. Each type is
planned, {made} and audited on its own, as its own dataset would be. Per-episode scene
records (their `referent` and `world` columns name each episode's type and world) and the one-word
counterfactual instructions are in `meta/scenes.parquet`; each type's confound audit is in
`meta/audit.json` under `referents`.
{sections}
## Provenance

| | |
|---|---|
{provenance.table()}

## Regenerate, and take the matching exams (one per type)

```
{provenance.command()}
{provenance.exam_command()}
{exams}
```
"""
    )


def write_exam(root: Path, referent: Referent, provenance: Provenance, report: dict, trials: int) -> None:
    """The exam's card: what it tests, its faces, how to take it, and its plan's audit."""
    from core.exam import FACES

    faces = "\n".join(f"| `{name}` | {text} |" for name, text in FACES.items())
    text = (
        FRONT_MATTER.format(referent=referent.name, kind="deconfounded").replace(
            "  data_files: data/*/*.parquet", "  data_files: trials.parquet"
        )
        + f"""
# Counterfactual exam: `{referent.name}`

{trials} oracle-solvable trials on the held-out `exam` random stream (scene hashes never
occur in a training split). Each trial holds the pixels, scene and robot pose fixed and changes
one word. Files: `exam.json` (format, scoring parameters, object geometry, referent spec, audit),
`trials.parquet` (one row per rollout: what a policy may see — scene, initial state, instruction)
and `answers.parquet` (the answer key, for the scorer only); the format is documented in the
generator's `core/exam.py` and docs/EXAM_FORMAT.md.

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
{provenance.table()}

## Regenerate

```
{provenance.command()}
```
"""
    )
    (root / CARD_PATH).write_text(text)
