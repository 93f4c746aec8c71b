"""Every axis in one set of weights: does one adapter, trained on several referent types at once,
read every kind of instruction?

python -m train.axes out=runs/axes                 # all three parts
python -m train.axes 'parts=[axes]' out=runs/axes  # one part (parts can run in different sittings)

Three parts, each reusing every finished stage (datasets, exams, training runs, reports) it
finds in `out`, so a killed run continues where it stopped:

* `axes` — a deconfounded training set per axis (`axes=`), one LoRA on their union (batches
  balanced across them), a held-out exam per axis taken by that one checkpoint, the `position`
  shortcut measured on each exam, and the single-axis checkpoint of docs/RESULTS.md on the
  object exam beside it (the two object exams are the same: same command, same seed);
* `loo` — the same recipe with one type left out of training (`left_out=`), examined on it;
* `tiers` — exposure on the object axis: a dataset where one object is only ever a distractor
  (`distractor_only=`) and one never appears (`holdout=`), one LoRA on it, and an exam whose
  targets are a trained object and those two, so each tier's obeyed-name is read off the swaps
  that name it.

Each part generates only the sets it uses. Results go to docs= together with those of parts an
earlier sitting wrote there (carried over from its results_axes.json, and said so), so the parts
can be run one at a time.

The recipe scales with the number of types trained: `steps_per_axis` steps each, the last
`cool` fraction cooling the learning rate to `lr_floor`. Results go to
docs/RESULTS_AXES.md, docs/results_axes.json and docs/axes.png; the trained checkpoints, when
small enough, to docs/checkpoints/.
"""

from __future__ import annotations

import json
import sys
from dataclasses import asdict, dataclass, field
from pathlib import Path

from core.exam import read
from eval.policies import FeatureMismatch
from gen.config import GenConfig
from jobs.cli import UserError, main
from referents import registry
from train.stages import Ledger, cell, commit, exam_report, gen_command, generate_once, train_once, value

PARTS = ("axes", "loo", "tiers")
AXES = ("object", "color", "category", "ordinal", "relation", "negation", "composition")
SINGLE_AXIS = "docs/checkpoints/deconfounded-lora"  # docs/RESULTS.md's object-axis weights
PICTURE = "axes.png"


@dataclass
class AxesOptions:
    parts: list[str] = field(default_factory=lambda: list(PARTS))  # which parts to run: axes, loo, tiers
    axes: list[str] = field(default_factory=lambda: list(AXES))  # referent types trained together
    # Left out in `loo`: ordinal, because no other type's instructions use its words (second, third, last
    # from the left), so nothing trained on the rest can carry over to it except the layout of a row.
    left_out: str = "ordinal"
    n: int = 300  # episodes per training set
    trials: int = 40  # trials per held-out exam
    steps_per_axis: int = 2000  # training steps per type trained (7 types: 14000)
    cool: float = 1 / 3  # the last this fraction of the steps cools the learning rate down
    lr_floor: float = 0.05
    tier_steps: int = 9000  # the object axis alone, as docs/RESULTS.md trains it
    distractor_only: str = "bottle"  # the exposure tier seen only as a distractor
    absent: str = "lemon"  # the tier never in the training data
    trained: str = "milk carton"  # the tier trained as a target, examined beside the other two
    tier_trials: int = 60  # trials of the tier exam (each tier needs >= 18 swaps naming it)
    replan: int = 5  # actions of each predicted chunk executed before the policy looks again
    image_size: int = 96
    seed: int = 0  # the training sets' seed (the exams' is seed + 1)
    commit_mb: float = 20.0  # checkpoints up to this size are copied to docs/checkpoints/
    out: str = "runs/axes"
    docs: str = "docs"
    train: bool = True  # false: no training; parts not finished in out= are reported as not run


def _check(options: AxesOptions) -> None:
    if not options.parts or any(p not in PARTS for p in options.parts):
        raise UserError(f"parts must be some of {', '.join(PARTS)}, got {options.parts}")
    unknown = [a for a in options.axes if a not in registry.available()]
    if unknown or len(options.axes) < 2 or len(set(options.axes)) != len(options.axes):
        raise UserError(
            f"axes must be two or more different referent types ({', '.join(registry.available())}), got {options.axes}"
        )
    if "loo" in options.parts and options.left_out not in options.axes:
        raise UserError(f"left_out={options.left_out!r} is not one of axes={options.axes}")
    for name in ("n", "trials", "steps_per_axis", "tier_steps", "tier_trials", "replan"):
        if getattr(options, name) < 1:
            raise UserError(f"{name} must be at least 1, got {getattr(options, name)}")
    if not 0 <= options.cool < 1 or not 0 <= options.lr_floor <= 1:
        raise UserError(f"cool must be in [0, 1) and lr_floor in [0, 1], got {options.cool} and {options.lr_floor}")
    tiers = (options.trained, options.distractor_only, options.absent)
    if "tiers" in options.parts and len(set(tiers)) != 3:
        raise UserError(f"trained, distractor_only and absent must be three different objects, got {tiers}")


def _stages(options: AxesOptions) -> dict[str, tuple[str, GenConfig]]:
    """Stage name -> (command, config) of every dataset and exam the chosen parts need."""
    root, stages = Path(options.out), {}
    data = set(options.axes) if "axes" in options.parts else set()
    exams = set(data)
    if "loo" in options.parts:
        data |= {axis for axis in options.axes if axis != options.left_out}
        exams.add(options.left_out)
    for axis in options.axes:
        if axis in data:
            args = (f"referent={axis}", f"n={options.n}", f"seed={options.seed}")
            stages[f"data {axis}"] = gen_command(args, root / "data" / axis, options.image_size)
        if axis in exams:
            args = (f"referent={axis}", f"n={options.trials}", "split=exam", f"seed={options.seed + 1}")
            stages[f"exam {axis}"] = gen_command(args, root / "exams" / axis, options.image_size)
    if "tiers" in options.parts:
        quoted = (f'"{options.absent}"', f'"{options.distractor_only}"', f'"{options.trained}"')
        args = ("referent=object", f"n={options.n}", f"seed={options.seed}", f"holdout=[{quoted[0]}]",
                f"distractor_only=[{quoted[1]}]")  # fmt: skip
        stages["data tiers"] = gen_command(args, root / "data" / "tiers", options.image_size)
        args = ("referent=object", f"n={options.tier_trials}", "split=exam", f"seed={options.seed + 1}",
                f"targets=[{','.join(quoted)}]")  # fmt: skip
        stages["exam tiers"] = gen_command(args, root / "exams" / "tiers", options.image_size)
    return stages


def _train(options: AxesOptions, name: str, datasets: list[Path], steps: int, ledger: Ledger, commands: list[str]) -> dict | None:
    """Train (or continue, or reuse) the LoRA run `name` on `datasets`; its log, or None when
    it is not finished and `train=false`."""
    from train.fit import LoraOptions, TrainConfig

    ckpt = Path(options.out) / "ckpt" / name
    decay = int(round(steps * options.cool))
    cfg = TrainConfig(
        dataset=[str(d) for d in datasets],
        out=str(ckpt),
        steps=steps,
        decay=decay,
        lr_floor=options.lr_floor,
        lora=LoraOptions(16),
        resume=True,
    )
    listed = ",".join(map(str, datasets))
    commands.append(
        f"python -m train 'dataset=[{listed}]' policy=tiny lora.rank=16 steps={steps} decay={decay} "
        f"lr_floor={options.lr_floor} out={ckpt}"
    )
    return train_once(cfg, ledger, f"train {name}", options.train)


def _row(report: dict, **extra: object) -> dict:
    faces = report["faces"]
    return {
        **extra,
        "faces": faces,
        "baseline": report.get("baseline"),
        "per_object": report.get("per_object"),
        **({"grounding": report["grounding"]} if "grounding" in report else {}),
    }


def run(options: AxesOptions) -> dict:
    _check(options)
    stages = _stages(options)
    from train.policy import MODEL_FILE  # torch loads only for valid input

    root, docs = Path(options.out), Path(options.docs)
    ledger, commands = Ledger(root), []
    results: dict = {"settings": asdict(options), "commands": commands, "not_run": []}
    exams = {}
    for name, (line, cfg) in stages.items():
        commands.append(line)
        generate_once(cfg, ledger, f"generate {name.split()[1]} {name.split()[0]}")
        if name.startswith("exam"):
            exams[name.split()[1]] = (read(str(cfg.out)), str(cfg.out))

    def examine(weights: Path, run_name: str, axis: str) -> dict:
        exam, exam_dir = exams[axis]
        out = root / "reports" / run_name / axis
        commands.append(f"python -m eval policy=ckpt:{weights} exam={exam_dir} replan={options.replan} workers=2 out={out}")
        return exam_report(exam, weights, exam.trials, out, options.replan, ledger, f"eval {run_name} on {axis}")

    data = {axis: Path(options.out) / "data" / axis for axis in options.axes}
    if "axes" in options.parts:
        log = _train(options, "axes", list(data.values()), options.steps_per_axis * len(options.axes), ledger, commands)
        if log is None:
            results["not_run"].append("axes")
        else:
            ckpt = root / "ckpt" / "axes"
            results["axes"] = {
                "rows": [_row(examine(ckpt, "axes", axis), axis=axis) for axis in options.axes],
                "final_loss": log["final_loss"],
                "loss_curve": [(h["step"], round(h["loss"], 5)) for h in log["history"]],
                "checkpoint": commit(ckpt / MODEL_FILE, docs / "checkpoints" / "axes-lora", options.commit_mb),
            }
            if "object" in options.axes and (Path(SINGLE_AXIS) / MODEL_FILE).is_file():
                try:
                    single = _row(examine(Path(SINGLE_AXIS), "single-axis", "object"), weights=SINGLE_AXIS)
                except FeatureMismatch as exc:  # e.g. another image_size than those weights were trained at
                    single = {"weights": SINGLE_AXIS, "skipped": str(exc)}
                results["axes"]["single_axis_object"] = single
    if "loo" in options.parts:
        kept = [axis for axis in options.axes if axis != options.left_out]
        name = f"without-{options.left_out}"
        log = _train(options, name, [data[a] for a in kept], options.steps_per_axis * len(kept), ledger, commands)
        if log is None:
            results["not_run"].append("loo")
        else:
            report = examine(root / "ckpt" / name, name, options.left_out)
            results["loo"] = {**_row(report, axis=options.left_out, trained_on=kept), "final_loss": log["final_loss"]}
    if "tiers" in options.parts:
        log = _train(options, "tiers", [root / "data" / "tiers"], options.tier_steps, ledger, commands)
        if log is None:
            results["not_run"].append("tiers")
        else:
            report = examine(root / "ckpt" / "tiers", "tiers", "tiers")
            results["tiers"] = {**_row(report), "tiers": _tiers(options, report)}
    results["timings_s"] = ledger.spent
    return results


def _tiers(options: AxesOptions, report: dict) -> dict:
    """Obeyed name per exposure tier: the swaps that name that object (the report's per-object
    table, with trial-resampled intervals)."""
    chance = report["faces"]["obeyed_name"]["chance"]
    named = (("target", options.trained), ("distractor_only", options.distractor_only), ("absent", options.absent))
    none = {"k": 0, "n": 0, "rate": None, "ci": [0.0, 1.0], "ci_trials": [0.0, 1.0]}
    return {
        tier: {"object": name, **report["per_object"].get(name, {}).get("obeyed_name", none), "chance": chance}
        for tier, name in named
    }


def write_docs(results: dict, docs: Path) -> None:
    docs.mkdir(parents=True, exist_ok=True)
    (docs / "results_axes.json").write_text(json.dumps(results, indent=2))
    s = results["settings"]
    lines = [
        "# Results: every axis in one set of weights",
        "",
        f"Generated by `python -m train.axes` ({', '.join(f'{k}={value(v)}' for k, v in s.items())}). "
        f"Each training set holds {s['n']} oracle demonstrations at {s['image_size']} px; each held-out exam {s['trials']} "
        "trials (task, a swap for every other alternative, occ, nonsense). Rates carry k/n and a 95% interval that "
        "resamples whole trials; the `position` shortcut is measured on the same exam.",
    ]
    axes = results.get("axes")
    if axes:
        lines += [
            "",
            "## One LoRA, every axis",
            "",
            "| axis | task | obeyed name (5 cm) | obeyed (2 cm) | obeyed (achieved) | true target | occ | nonsense | chance "
            "| shortcut obeyed (5 cm) | above the shortcut |",
            "|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        for r in axes["rows"]:
            lines.append(_axis_line(r["axis"], r))
        single = axes.get("single_axis_object")
        if single and "skipped" in single:
            lines += ["", f"docs/RESULTS.md's single-axis weights were not compared: {single['skipped']}."]
        elif single:
            lines += [
                "",
                f"The object axis with docs/RESULTS.md's single-axis weights (`{single['weights']}`) on the same object exam: "
                f"obeyed name {cell(single['faces']['obeyed_name'])} at 5 cm, against "
                f"{cell(next(r for r in axes['rows'] if r['axis'] == 'object')['faces']['obeyed_name'])} sharing one set of "
                "weights with the other axes.",
            ]
        plot(results, docs / PICTURE)
        lines += ["", f"![obeyed name per axis]({PICTURE})"]
    loo = results.get("loo")
    if loo:
        trained = next((r for r in (axes or {}).get("rows", []) if r["axis"] == loo["axis"]), None)
        lines += [
            "",
            f"## Leave one out: {loo['axis']}",
            "",
            f"Trained on {', '.join(loo['trained_on'])}; examined on {loo['axis']}: "
            f"obeyed name {cell(loo['faces']['obeyed_name'])}"
            + (f" against {cell(trained['faces']['obeyed_name'])} when trained with it" if trained else "")
            + f"; chance {loo['faces']['obeyed_name']['chance']:.0%}.",
        ]
    tiers = results.get("tiers")
    if tiers:
        lines += [
            "",
            "## Exposure tiers (object axis)",
            "",
            "| tier | object | obeyed name (5 cm) | chance |",
            "|---|---|---|---|",
        ]
        for tier, t in tiers["tiers"].items():
            lines.append(f"| {tier.replace('_', ' ')} | {t['object']} | {cell(t)} | {t['chance']:.0%} |")
    if results.get("carried"):
        lines += ["", f"Carried over from the results an earlier sitting wrote here: {', '.join(results['carried'])}."]
    if results["not_run"]:
        lines += ["", f"Not run (no finished training in `{s['out']}`): {', '.join(results['not_run'])}."]
    lines += ["", "Commands, in order:", "", "```", *dict.fromkeys(results["commands"]), "```", ""]
    lines += ["Wall time per stage (s, this 2-core machine, summed over the invocations that did its work):", ""]
    lines += [f"- {k}: {v}" for k, v in results["timings_s"].items()]
    (docs / "RESULTS_AXES.md").write_text("\n".join(lines) + "\n")


def _axis_line(axis: str, r: dict) -> str:
    f, base = r["faces"], r.get("baseline") or {}
    levels = f["obeyed_name"].get("by_level") or {}
    by = [cell(levels[lv]) if lv in levels else "—" for lv in ("2cm", "achieved")]
    shortcut = base.get("obeyed_name")
    above = "—"
    if shortcut:
        lo = (f["obeyed_name"].get("ci_trials") or f["obeyed_name"]["ci"])[0]
        hi = (shortcut.get("ci_trials") or shortcut["ci"])[1]
        above = "yes" if lo > hi else "no"
    return (
        f"| {axis} | {cell(f['task'])} | {cell(f['obeyed_name'])} | {by[0]} | {by[1]} | {cell(f['true_target'])} "
        f"| {cell(f['occ'])} | {cell(f['nonsense'])} | {f['obeyed_name']['chance']:.0%} "
        f"| {cell(shortcut) if shortcut else '—'} | {above} |"
    )


def plot(results: dict, path: Path) -> None:
    """Obeyed name per axis (one LoRA), the shortcut and chance beside it; the left-out type."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    rows = results["axes"]["rows"]
    x = np.arange(len(rows))
    fig, ax = plt.subplots(figsize=(1.2 * len(rows) + 2, 3.8))

    def bars(faces: list[dict], offset: float, label: str, color: str) -> None:
        rates = [f["rate"] for f in faces]
        lo, hi = zip(*((f.get("ci_trials") or f["ci"]) for f in faces))
        err = [[r - a for r, a in zip(rates, lo)], [b - r for r, b in zip(rates, hi)]]
        ax.bar(x + offset, rates, 0.35, yerr=err, capsize=3, label=label, color=color)

    bars([r["faces"]["obeyed_name"] for r in rows], -0.18, "one LoRA, all axes", "tab:blue")
    shortcut = [(r.get("baseline") or {}).get("obeyed_name") for r in rows]
    if all(shortcut):
        bars(shortcut, 0.18, "position shortcut", "tab:gray")
    for i, r in enumerate(rows):
        ax.hlines(r["faces"]["obeyed_name"]["chance"], i - 0.4, i + 0.4, colors="k", linestyles=":")
    loo = results.get("loo")
    if loo and loo["axis"] in [r["axis"] for r in rows]:
        i = [r["axis"] for r in rows].index(loo["axis"])
        ax.plot(i - 0.18, loo["faces"]["obeyed_name"]["rate"], "rv", markersize=9, label=f"{loo['axis']} left out")
    ax.set_xticks(x, [r["axis"] for r in rows])
    ax.set(ylabel="obeyed name (5 cm)", ylim=(0, 1.05), title="Held-out exams; dotted: chance")
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def carried_over(results: dict, previous_file: Path) -> dict:
    """`results` with the parts it lacks taken from the results already written in docs=: a part
    finished in an earlier sitting, whose out= may be gone since, stays reported (and says so)."""
    try:
        previous = json.loads(previous_file.read_text())
    except (OSError, ValueError):
        return results
    carried = [part for part in PARTS if part not in results and part in previous]
    if not carried:
        return results
    return {
        **results,
        **{part: previous[part] for part in carried},
        "carried": carried,
        "not_run": [part for part in results["not_run"] if part not in carried],
        "commands": [*previous.get("commands", []), *results["commands"]],
        "timings_s": {**previous.get("timings_s", {}), **results["timings_s"]},
    }


def axes(options: AxesOptions) -> None:
    results = carried_over(run(options), Path(options.docs) / "results_axes.json")
    write_docs(results, Path(options.docs))
    print((Path(options.docs) / "RESULTS_AXES.md").read_text())


if __name__ == "__main__":
    sys.exit(main("python -m train.axes", AxesOptions, axes, doc=__doc__))
