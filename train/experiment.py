"""The end-to-end experiment: does deconfounded data make a policy read its instruction?

python -m train.experiment n=300 steps=9000 decay=3000 lr_floor=0.05 trials=40 image_size=96 out=runs/experiment

On the object axis: generate a confounded training set (`confound=position`: the target always
in the canonical slot) and a deconfounded one of the same size, fine-tune the tiny policy on
each (LoRA; `finetunes=[lora,full]` adds the full fine-tune), take the same held-out exam with
every checkpoint, and write `docs/RESULTS.md`, `docs/results.json` and the training curves
(`docs/training_curves.png`: loss, and obeyed-name on the exam's first `curve_trials` trials at
the kept checkpoints).
Checkpoints whose trainable weights fit in `commit_mb` are copied to `docs/checkpoints/`, so
the exam can be re-run without retraining. Every stage whose output already exists is reused
(a report while the weights it was taken with are unchanged), so a killed experiment continues
where it stopped, and a larger `steps=` continues finished training runs from their last state
before the cool-down (the same as training that long from the start: tests/test_train.py).
`train=false` writes the docs from the finished runs alone.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

from core.exam import read
from gen.cli import Failed, UserError, main
from gen.config import GenConfig, parse
from train.stages import Ledger, brief, cell, commit, exam_report, generate_once, schedule, train_log, value

FINETUNES = ("lora", "full", "frozen")
CURVES_PICTURE = "training_curves.png"
TRAINING_SETS = ("deconfounded", "confounded")  # the headline first, so a stopped run has it


@dataclass
class ExperimentOptions:
    n: int = 300  # episodes in each training set
    steps: int = 9000  # training steps per checkpoint; raising it later extends finished runs
    decay: int = 3000  # the last this many steps cool the learning rate down to lr_floor of its peak (0: none)
    lr_floor: float = 0.05  # 1: a constant learning rate
    trials: int = 40  # trials in the held-out exam
    replan: int = 5  # actions of each predicted chunk executed before the policy looks again
    curve_points: int = 3  # checkpoints kept per training run for the curves (the last is the final model)
    curve_trials: int = 10  # exam trials each curve point takes
    commit_mb: float = 20.0  # checkpoints up to this size are copied to docs/checkpoints/
    image_size: int = 96  # camera frames in pixels, for the data, the exam and the policy
    out: str = "runs/experiment"  # data, checkpoints and reports; finished stages found here are reused
    seed: int = 0  # the training sets' seed (the exam's is seed + 1)
    # Fine-tunes trained on each set (lora, full, frozen). LoRA alone keeps the run near 2.5 h on 2 cores;
    # adding full (~75 min per 9000-step run: 2.0 steps/s) takes it past 3 h.
    finetunes: list[str] = field(default_factory=lambda: ["lora"])
    data: list[str] = field(default_factory=lambda: list(TRAINING_SETS))  # the training sets fine-tuned on, in this order
    docs: str = "docs"  # where RESULTS.md and results.json go
    train: bool = True  # false: no training; runs not finished in out= are listed as not run


def _datasets(options: ExperimentOptions) -> dict[str, tuple[list[str], Path]]:
    """Stage name -> (`python -m gen` options, folder): the two training sets and the exam."""
    root, size = Path(options.out), f"image_size={options.image_size}"
    train = ["referent=object", f"n={options.n}", f"seed={options.seed}", size]
    return {
        "confounded": ([*train, "confound=position"], root / "data" / "confounded"),
        "deconfounded": (train, root / "data" / "deconfounded"),
        "exam": (["referent=object", f"n={options.trials}", "split=exam", f"seed={options.seed + 1}", size], root / "exam"),
    }


def _configs(options: ExperimentOptions) -> dict[str, GenConfig]:
    """Every stage's generation config, validated before anything runs."""
    counts = ("steps", "trials", "replan", "curve_points", "curve_trials")  # n, image_size: checked by `python -m gen`
    for name in counts:
        if getattr(options, name) < 1:
            raise UserError(f"{name} must be at least 1, got {getattr(options, name)}")
    if options.decay < 0:
        raise UserError(f"decay must be at least 0, got {options.decay}")
    if not 0 <= options.lr_floor <= 1:
        raise UserError(f"lr_floor is a fraction of the peak learning rate, between 0 and 1; got {options.lr_floor}")
    if not options.data or any(d not in TRAINING_SETS for d in options.data):
        raise UserError(f"data must be some of {', '.join(TRAINING_SETS)}, got {options.data}")
    unknown = [f for f in options.finetunes if f not in FINETUNES]
    if unknown or not options.finetunes:
        raise UserError(f"finetunes must be some of {', '.join(FINETUNES)}, got {options.finetunes}")
    return {name: parse([*args, f"out={out}", "overwrite=true"]) for name, (args, out) in _datasets(options).items()}


def run(options: ExperimentOptions) -> dict:
    configs = _configs(options)
    from train.fit import LoraOptions, TrainConfig, fit, kept_steps, snapshot_file  # torch loads only for valid input
    from train.policy import MODEL_FILE

    root, stages = Path(options.out), _datasets(options)
    commands: list[str] = []
    ledger = Ledger(root)
    for name, (args, out) in stages.items():
        commands.append("python -m gen " + " ".join(args) + f" out={out}")
        generate_once(configs[name], ledger, f"generate {name}")
    exam_dir = stages["exam"][1]
    exam = read(exam_dir)
    curve_rows = exam.trials[exam.trials["trial"] < options.curve_trials]
    keep_every = options.steps // options.curve_points if options.curve_points > 1 else 0

    rows, not_run = [], []
    for name in options.data:
        data = stages[name][1]
        for finetune in options.finetunes:
            run_name = f"{name}-{finetune}"
            ckpt = root / "ckpt" / run_name
            cfg = TrainConfig(
                dataset=str(data),
                out=str(ckpt),
                finetune=finetune,
                steps=options.steps,
                decay=options.decay,
                lr_floor=options.lr_floor,
                lora=LoraOptions(16),
                keep_every=keep_every,
                resume=True,
            )
            commands.append(
                f"python -m train dataset={data} policy=tiny finetune={finetune} lora.rank=16 steps={options.steps} "
                f"decay={options.decay} lr_floor={options.lr_floor} keep_every={keep_every} out={ckpt}"
            )
            log = train_log(ckpt)
            trained = log["steps"] if log else 0
            if trained > options.steps:
                raise UserError(f"{ckpt} holds a {trained}-step run, more than steps={options.steps}; choose another out=")
            if log is None or schedule(log["config"]) != schedule(asdict(cfg)):
                if not options.train:
                    not_run.append(run_name)
                    continue
                t = time.perf_counter()
                try:  # a killed run, or a finished shorter one, continues from its last matching state
                    fit(cfg)
                except ValueError as exc:  # the dataset or an earlier run's checkpoint does not fit
                    raise Failed(f"training {ckpt}: {exc}") from None
                ledger.spend(f"train {run_name}", t)
                log = train_log(ckpt)
            report_dir = root / "reports" / run_name / f"step-{options.steps}"
            commands.append(
                f"python -m eval policy=ckpt:{ckpt} exam={exam_dir} replan={options.replan} workers=2 out={report_dir}"
            )
            report = exam_report(exam, ckpt, exam.trials, report_dir, options.replan, ledger, f"eval {run_name}")
            curve = []
            for step in [*kept_steps(ckpt, options.steps), options.steps]:
                weights = ckpt / (MODEL_FILE if step == options.steps else snapshot_file(step))
                point_dir = root / "curves" / run_name / f"step-{step}"
                point = exam_report(exam, weights, curve_rows, point_dir, options.replan, ledger, f"curve {run_name}", False)
                curve.append({"step": step, "obeyed_name": brief(point["faces"]["obeyed_name"])})
            rows.append(
                {
                    "data": name,
                    "finetune": finetune,
                    "faces": report["faces"],
                    **({"grounding": report["grounding"]} if "grounding" in report else {}),
                    "init_value_trusted": report["init_value"]["trusted"],
                    "reach_probe": report["reach_probe"],
                    "distances": report["distances"],
                    "final_loss": log["final_loss"],
                    "trainable_parameters": log["trainable_parameters"],
                    "loss_curve": [(h["step"], round(h["loss"], 5)) for h in log["history"]],
                    "heldout_curve": curve,
                    "checkpoint": commit(ckpt / MODEL_FILE, Path(options.docs) / "checkpoints" / run_name, options.commit_mb),
                }
            )
    if rows:  # the measured shortcut on the same exam: what a position-reading policy scores
        rows.append({"data": None, "finetune": None, "policy": "position", "faces": report["baseline"]})
    return {"settings": asdict(options), "rows": rows, "not_run": not_run, "commands": commands, "timings_s": ledger.spent}


def write_docs(results: dict, docs: Path) -> None:
    docs.mkdir(parents=True, exist_ok=True)
    (docs / "results.json").write_text(json.dumps(results, indent=2))
    s = results["settings"]
    lines = [
        "# Results: deconfounded data x low-rank update, object axis",
        "",
        f"Generated by `python -m train.experiment` ({', '.join(f'{k}={value(v)}' for k, v in s.items())}). "
        f"Training sets: {s['n']} oracle demonstrations each at {s['image_size']} px; the held-out exam has "
        f"{s['trials']} trials (task, a swap for every other object, occ, nonsense). Rates carry k/n and a 95% "
        "interval that resamples whole trials (a trial's rollouts share its scene); chance for obeyed-name/true-target "
        "is 1 / (objects in the scene), and the `position` row is the measured shortcut on the same exam. Obeyed name "
        "is given at three levels: landed within 5 cm, within 2 cm, achieved the program on the named object.",
        "",
        "| data | fine-tune | task | obeyed name (5 cm) | obeyed (2 cm) | obeyed (achieved) | grounded (first frame) "
        "| true target | occ | nonsense | chance |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results["rows"]:
        f = r["faces"]
        levels = f["obeyed_name"].get("by_level") or {}
        by = [cell(levels[lv]) if lv in levels else "—" for lv in ("2cm", "achieved")]
        who = (r["data"], r["finetune"]) if r["data"] else ("—", "`position` (shortcut)")
        grounded = cell(r["grounding"]) if "grounding" in r else "—"
        lines.append(
            f"| {who[0]} | {who[1]} | {cell(f['task'])} | {cell(f['obeyed_name'])} | {by[0]} | {by[1]} | {grounded} "
            f"| {cell(f['true_target'])} | {cell(f['occ'])} | {cell(f['nonsense'])} | {f['obeyed_name']['chance']:.0%} |"
        )
    if results.get("not_run"):
        lines += ["", f"Not run (no finished training in `{s['out']}`): {', '.join(results['not_run'])}."]
    trained = [r for r in results["rows"] if r["data"]]
    if trained:
        plot_curves(trained, docs / CURVES_PICTURE)
        lines += [
            "",
            f"![training curves]({CURVES_PICTURE})",
            "",
            f"Training curves: loss (left) and obeyed-name at 5 cm on the exam's first {s['curve_trials']} trials at "
            "kept checkpoints (right; the last point is the final model).",
            "",
            "Final checkpoints committed (re-run the exam with `python -m eval policy=ckpt:<file> exam=<exam>`): "
            + (", ".join(f"`{r['checkpoint']}`" for r in trained if r.get("checkpoint")) or "none")
            + "; a checkpoint over "
            f"{s['commit_mb']:g} MB (a full fine-tune carries the whole text tower) is not committed.",
        ]
    lines += [
        "",
        "Commands, in order:",
        "",
        "```",
        *results["commands"],
        "```",
        "",
        "Wall time per stage (s, this 2-core machine, summed over the invocations that did its work):",
        "",
    ]
    lines += [f"- {k}: {v}" for k, v in results["timings_s"].items()]
    (docs / "RESULTS.md").write_text("\n".join(lines) + "\n")


def plot_curves(rows: list[dict], path: Path) -> None:
    """Loss and held-out obeyed-name against training steps, one line per training run."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (loss_ax, obey_ax) = plt.subplots(1, 2, figsize=(10, 3.6))
    for r in rows:
        label = f"{r['data']} {r['finetune']}"
        steps, losses = zip(*r["loss_curve"])
        loss_ax.plot(steps, losses, label=label)
        points = r["heldout_curve"]
        rates = [p["obeyed_name"]["rate"] for p in points]
        lo, hi = zip(*(p["obeyed_name"].get("ci_trials") or p["obeyed_name"]["ci"] for p in points))
        x = [p["step"] for p in points]
        obey_ax.errorbar(
            x,
            rates,
            yerr=[[r - a for r, a in zip(rates, lo)], [b - r for r, b in zip(rates, hi)]],
            marker="o",
            capsize=3,
            label=label,
        )
    loss_ax.set(xlabel="step", ylabel="training loss", yscale="log", title="loss")
    obey_ax.set(xlabel="step", ylabel="obeyed name (5 cm)", ylim=(0, 1), title="held-out obeyed name")
    loss_ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def experiment(options: ExperimentOptions) -> None:
    results = run(options)
    write_docs(results, Path(options.docs))
    print((Path(options.docs) / "RESULTS.md").read_text())


if __name__ == "__main__":
    sys.exit(main("python -m train.experiment", ExperimentOptions, experiment, doc=__doc__))
