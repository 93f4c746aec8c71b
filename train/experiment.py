"""The end-to-end experiment: does deconfounded data make a policy read its instruction?

python -m train.experiment n=300 steps=9000 decay=3000 lr_floor=0.05 trials=40 image_size=96 out=runs/experiment
python -m train.experiment world=libero_object repeats=2            # the same proof in LIBERO-Object's world

On one world's object axis (`world=native`: the object referent on our table; a LIBERO world:
its LIBERO-task referent, `libero_object` on LIBERO-Object's floor): generate a confounded
training set (natively `confound=position`: every target in the canonical slot; in LIBERO's world
`confound=layout`: every scene laid out as LIBERO's own task of its target is, as LIBERO's
demonstrations are) and a deconfounded one of the same size,
fine-tune the tiny policy on each (LoRA; `finetunes=[lora,full]` adds the full fine-tune;
`repeats=2` trains the deconfounded run again on its own data, with its own seed), take the same
held-out exams with every checkpoint — the deconfounded `split=exam` exam, and in a LIBERO world
the canonical exam on LIBERO's own initial states (`states` per task, `gen.canonical`) — with the
`position` shortcut measured on each (and, where the referent's confounded data ties each name
to a place of its own, the `named_place` shortcut, with every run's obeyed name on the swaps it
does not obey), and write the results (`docs/RESULTS.md` and
`docs/results.json` natively, `docs/RESULTS_LIBERO.md` and `docs/results_libero.json` for
LIBERO-Object) with the training curves (loss, and obeyed-name on the first exam's first
`curve_trials` trials at the kept checkpoints) and, in a LIBERO world, a picture of the policies'
faces on the canonical exam.
Checkpoints whose trainable weights fit in `commit_mb` are copied to `docs/checkpoints/`, so
the exam can be re-run without retraining. Every stage whose output already exists is reused
(a report while the weights it was taken with are unchanged), so a killed experiment continues
where it stopped, and a larger `steps=` continues finished training runs from their last state
before the cool-down (the same as training that long from the start: tests/sim/test_train.py).
`train=false` writes the docs from the finished runs alone.
"""

from __future__ import annotations

import json
import sys
from dataclasses import asdict, dataclass, field
from pathlib import Path

from core import worlds
from core.exam import Exam, read
from gen.config import GenConfig, parse
from jobs.cli import Failed, UserError, main
from referents import registry
from train.stages import (
    Ledger,
    brief,
    canonical_once,
    cell,
    commit,
    exam_report,
    generate_once,
    recipe,
    reference_report,
    train_log,
    value,
)

FINETUNES = ("lora", "full", "frozen")
TRAINING_SETS = ("deconfounded", "confounded")  # the headline first, so a stopped run has it
EXAM, CANONICAL = "exam", "canonical"  # the deconfounded held-out exam; LIBERO's own initial states


@dataclass
class ExperimentOptions:
    world: str = "native"  # native: the object axis on our table; a LIBERO world (libero_object): its own object axis
    n: int = 300  # episodes in each training set
    steps: int = 9000  # training steps per checkpoint; raising it later extends finished runs
    decay: int = 3000  # the last this many steps cool the learning rate down to lr_floor of its peak (0: none)
    lr_floor: float = 0.05  # 1: a constant learning rate
    trials: int = 40  # trials in the held-out exam
    states: int = 4  # a LIBERO world's canonical exam: LIBERO's initial states per task (drawn with seed + 1)
    replan: int = 5  # actions of each predicted chunk executed before the policy looks again
    curve_points: int = 3  # checkpoints kept per training run for the curves (the last is the final model)
    curve_trials: int = 10  # exam trials each curve point takes
    commit_mb: float = 20.0  # checkpoints up to this size are copied to docs/checkpoints/
    image_size: int = 96  # camera frames in pixels, for the data, the exams and the policy
    # The pointer loss (train/fit.py point_weight): default 1 in a LIBERO world, where the tiny policy
    # did not learn to find the named grocery without it, and 0 natively (docs/RESULTS.md was made without).
    point_weight: float | None = None
    out: str | None = None  # data, checkpoints and reports (default runs/experiment, runs/experiment-<world>)
    seed: int = 0  # the training sets' seed (the exams' is seed + 1)
    repeats: int = 1  # deconfounded runs, each on its own data with its own seed (seed, seed + 2, seed + 4, ...)
    # Fine-tunes trained on each set (lora, full, frozen). LoRA alone keeps the run near 2.5 h on 2 cores;
    # adding full (~75 min per 9000-step run: 2.0 steps/s) takes it past 3 h.
    finetunes: list[str] = field(default_factory=lambda: ["lora"])
    data: list[str] = field(default_factory=lambda: list(TRAINING_SETS))  # the training sets fine-tuned on, in this order
    docs: str = "docs"  # where the results go
    train: bool = True  # false: no training; runs not finished in out= are listed as not run


@dataclass(frozen=True)
class Names:
    """Where a world's results go in docs/."""

    results: str
    json: str
    curves: str
    faces: str


def names(world: str) -> Names:
    """docs/RESULTS.md natively; docs/RESULTS_LIBERO.md for LIBERO-Object (RESULTS_<WORLD>.md for another)."""
    if world == "native":
        return Names("RESULTS.md", "results.json", "training_curves.png", "")
    tag = "libero" if world == "libero_object" else world
    return Names(f"RESULTS_{tag.upper()}.md", f"results_{tag}.json", f"training_curves_{tag}.png", f"{tag}_faces.png")


def _referent(world: str) -> str:
    """The object axis of `world`: the object referent natively, a LIBERO world's LIBERO-task type."""
    if world == "native":
        return "object"
    found = [r for r in registry.of_world(world) if registry.load(r).code.canonical is not None]
    if not found:
        usable = ", ".join(["native", *(w for w in worlds.names() if worlds.world(w).suite and _has_canonical(w))])
        raise UserError(f"world={world} has no referent type that lays out LIBERO's tasks; worlds: {usable}")
    return found[0]


def _has_canonical(world: str) -> bool:
    return any(registry.load(r).code.canonical is not None for r in registry.of_world(world))


def _out(options: ExperimentOptions) -> Path:
    return Path(options.out or ("runs/experiment" if options.world == "native" else f"runs/experiment-{options.world}"))


def _seeds(options: ExperimentOptions) -> list[int]:
    return [options.seed + 2 * k for k in range(options.repeats)]


def _set_name(data: str, repeat: int) -> str:
    """A training set's name: `deconfounded`, and `deconfounded-seed<k>` for its repeats."""
    return data if repeat == 0 else f"{data}-repeat{repeat}"


def _datasets(options: ExperimentOptions) -> dict[str, tuple[list[str], Path]]:
    """Stage name -> (`python -m gen` options, folder): the training sets and the exam."""
    root, size, referent = _out(options), f"image_size={options.image_size}", _referent(options.world)
    train = [f"referent={referent}", f"n={options.n}"]
    confound = "layout" if "layout" in registry.load(referent).code.CONFOUNDS else "position"
    stages = {"confounded": ([*train, f"seed={options.seed}", size, f"confound={confound}"], root / "data" / "confounded")}
    for k, seed in enumerate(_seeds(options)):
        stages[_set_name("deconfounded", k)] = ([*train, f"seed={seed}", size], root / "data" / _set_name("deconfounded", k))
    exam = [f"referent={referent}", f"n={options.trials}", "split=exam", f"seed={options.seed + 1}", size]
    stages[EXAM] = (exam, root / "exam")
    return stages


def _configs(options: ExperimentOptions) -> dict[str, GenConfig]:
    """Every stage's generation config, validated before anything runs."""
    try:
        world = worlds.world(options.world)
    except worlds.UnknownWorld as exc:
        raise UserError(str(exc)) from None
    _referent(world.name)
    counts = ("steps", "trials", "replan", "curve_points", "curve_trials", "repeats")  # n, image_size: checked by `python -m gen`
    for name in counts:
        if getattr(options, name) < 1:
            raise UserError(f"{name} must be at least 1, got {getattr(options, name)}")
    if world.suite and not 1 <= options.states <= 50:
        raise UserError(f"states must be between 1 and 50 (LIBERO's initial states per task), got {options.states}")
    if options.decay < 0:
        raise UserError(f"decay must be at least 0, got {options.decay}")
    if options.point_weight is not None and options.point_weight < 0:
        raise UserError(f"point_weight must be at least 0, got {options.point_weight}")
    if not 0 <= options.lr_floor <= 1:
        raise UserError(f"lr_floor is a fraction of the peak learning rate, between 0 and 1; got {options.lr_floor}")
    if not options.data or any(d not in TRAINING_SETS for d in options.data):
        raise UserError(f"data must be some of {', '.join(TRAINING_SETS)}, got {options.data}")
    unknown = [f for f in options.finetunes if f not in FINETUNES]
    if unknown or not options.finetunes:
        raise UserError(f"finetunes must be some of {', '.join(FINETUNES)}, got {options.finetunes}")
    # resume=true: a generation killed with the experiment continues (a finished one is skipped: generate_once)
    stages = _datasets(options).items()
    return {name: parse([*args, f"out={out}", "overwrite=true", "resume=true"]) for name, (args, out) in stages}


def _canonical(options: ExperimentOptions, ledger: Ledger, commands: list[str]) -> Path | None:
    """A LIBERO world's canonical exam (gen.canonical), made once; None natively."""
    if not worlds.world(options.world).suite:
        return None
    out = _out(options) / CANONICAL
    return canonical_once(options.world, options.states, options.seed + 1, options.image_size, out, ledger,
                          "generate canonical", commands)  # fmt: skip


def _runs(options: ExperimentOptions) -> list[tuple[str, str, int]]:
    """(training set, fine-tune, training seed) of every run, headline first."""
    runs = []
    for data in options.data:
        seeds = _seeds(options) if data == "deconfounded" else [options.seed]
        runs += [(_set_name(data, k), finetune, seed) for finetune in options.finetunes for k, seed in enumerate(seeds)]
    return runs


def _point_weight(options: ExperimentOptions) -> float:
    if options.point_weight is not None:
        return options.point_weight
    return 0.0 if options.world == "native" else 1.0


def run(options: ExperimentOptions) -> dict:
    configs = _configs(options)
    from train.fit import LoraOptions, TrainConfig, fit, kept_steps, snapshot_file  # torch loads only for valid input
    from train.policy import MODEL_FILE

    root, stages = _out(options), _datasets(options)
    commands: list[str] = []
    ledger = Ledger(root)
    for name, (args, out) in stages.items():
        commands.append("python -m gen " + " ".join(args) + f" out={out}")
        generate_once(configs[name], ledger, f"generate {name}")
    exams = {EXAM: stages[EXAM][1]}
    canonical = _canonical(options, ledger, commands)
    if canonical is not None:
        exams[CANONICAL] = canonical
    loaded = {name: read(folder) for name, folder in exams.items()}
    curve_rows = loaded[EXAM].trials[loaded[EXAM].trials["trial"] < options.curve_trials]
    keep_every = options.steps // options.curve_points if options.curve_points > 1 else 0
    places = _named_places(_referent(options.world), exams, loaded, root, ledger, commands)

    rows, not_run, baselines = [], [], {}
    for data_name, finetune, seed in _runs(options):
        data = stages[data_name][1]
        run_name = f"{data_name}-{finetune}"
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
            point_weight=_point_weight(options),
            seed=seed,
            resume=True,
        )
        seeded = f" seed={seed}" if seed else ""
        pointed = f" point_weight={value(cfg.point_weight)}" if cfg.point_weight else ""
        commands.append(
            f"python -m train dataset={data} policy=tiny finetune={finetune} lora.rank=16 steps={options.steps} "
            f"decay={options.decay} lr_floor={options.lr_floor} keep_every={keep_every}{pointed}{seeded} out={ckpt}"
        )
        log = train_log(ckpt)
        trained = log["steps"] if log else 0
        if trained > options.steps:
            raise UserError(f"{ckpt} holds a {trained}-step run, more than steps={options.steps}; choose another out=")
        if log is None or recipe(log["config"]) != recipe(asdict(cfg)):
            if not options.train:
                not_run.append(run_name)
                continue
            try:  # a killed run, or a finished shorter one, continues from its last matching state
                with ledger.timing(f"train {run_name}"):
                    fit(cfg)
            except ValueError as exc:  # the dataset or an earlier run's checkpoint does not fit
                raise Failed(f"training {ckpt}: {exc}") from None
            log = train_log(ckpt)
        curve = []
        for step in [*kept_steps(ckpt, options.steps), options.steps]:
            weights = ckpt / (MODEL_FILE if step == options.steps else snapshot_file(step))
            point_dir = root / "curves" / run_name / f"step-{step}"
            point = exam_report(loaded[EXAM], weights, curve_rows, point_dir, options.replan, ledger, f"curve {run_name}", False)
            curve.append({"step": step, "obeyed_name": brief(point["faces"]["obeyed_name"])})
        for exam_name, folder in exams.items():
            # natively reports/<run>/step-N, as the object-axis results were made; a LIBERO world's per exam
            report_dir = root / "reports" / run_name / ("" if canonical is None else exam_name) / f"step-{options.steps}"
            commands.append(f"python -m eval policy=ckpt:{ckpt} exam={folder} replan={options.replan} workers=2 out={report_dir}")
            report = exam_report(loaded[exam_name], ckpt, loaded[exam_name].trials, report_dir, options.replan, ledger,
                                 f"eval {run_name} {exam_name}")  # fmt: skip
            baselines[exam_name] = report["baseline"]
            beyond = {}
            if exam_name in places:
                beyond["beyond_named_place"] = _beyond(loaded[exam_name], report_dir, places[exam_name][1])
            rows.append(
                {
                    "data": data_name,
                    "finetune": finetune,
                    "seed": seed,
                    "exam": exam_name,
                    "faces": report["faces"],
                    **({"grounding": report["grounding"]} if "grounding" in report else {}),
                    "init_value_trusted": report["init_value"]["trusted"],
                    "reach_probe": report["reach_probe"],
                    "distances": report["distances"],
                    "per_object": report.get("per_object"),
                    **beyond,
                    "final_loss": log["final_loss"],
                    "trainable_parameters": log["trainable_parameters"],
                    "loss_curve": [(h["step"], round(h["loss"], 5)) for h in log["history"]],
                    "heldout_curve": curve,
                    "checkpoint": commit(
                        ckpt / MODEL_FILE, Path(options.docs) / "checkpoints" / _committed(options, run_name), options.commit_mb
                    ),  # fmt: skip
                }
            )
    for exam_name, faces in baselines.items():  # the measured shortcut on the same exam: what a position-reading policy scores
        rows.append({"data": None, "finetune": None, "policy": "position", "exam": exam_name, "faces": faces})
    for exam_name, (report, _) in places.items():  # the name read as a place: what a policy that learnt each name's place scores
        rows.append({"data": None, "finetune": None, "policy": "named_place", "exam": exam_name, "faces": report["faces"]})
    settings = asdict(options) | {"out": str(root), "point_weight": _point_weight(options)}
    return {"settings": settings, "rows": rows, "not_run": not_run, "commands": commands, "timings_s": ledger.spent}


def _named_places(
    referent: str, exams: dict[str, Path], loaded: dict[str, Exam], root: Path, ledger: Ledger, commands: list[str]
) -> dict[str, tuple[dict, dict[int, bool]]]:
    """Exam -> the `named_place` shortcut's report and which of its swaps it obeyed, where the referent's
    confounded data ties each name to a place of its own (LIBERO-Object: two); {} where it does not."""
    from core.products import ROLLOUTS
    from eval.scoring.score import swaps_obeyed
    from eval.sims.log import read_logs

    if registry.load(referent).code.named_place is None:
        return {}
    measured = {}
    for exam_name, folder in exams.items():
        out = root / "reports" / "named_place" / exam_name
        commands.append(f"python -m eval policy=named_place exam={folder} workers=2 out={out}")
        report = reference_report(loaded[exam_name], "named_place", out, ledger, f"named_place {exam_name}")
        measured[exam_name] = (report, swaps_obeyed(loaded[exam_name], read_logs(out / ROLLOUTS)[0]))
    return measured


def _beyond(exam: Exam, report_dir: Path, place: dict[int, bool]) -> dict:
    """Obeyed name (5 cm) on the swaps the `named_place` shortcut does not obey: there a name read as a
    place leads elsewhere, so only reading it finds the object."""
    from core.products import ROLLOUTS
    from eval.scoring.score import clustered_rate, swaps_obeyed
    from eval.sims.log import read_logs

    mine, trial = swaps_obeyed(exam, read_logs(report_dir / ROLLOUTS)[0]), exam.trials.set_index("row")["trial"]
    rows = [row for row, obeyed in place.items() if not obeyed]
    return clustered_rate([float(mine[row]) for row in rows], [int(trial[row]) for row in rows])


def _committed(options: ExperimentOptions, run_name: str) -> str:
    """A run's folder under docs/checkpoints/: its name natively, `<world>-<name>` in another world."""
    return run_name if options.world == "native" else f"{options.world}-{run_name}"


def write_docs(results: dict, docs: Path) -> None:
    s = results["settings"]
    world = s.get("world", "native")
    named = names(world)
    docs.mkdir(parents=True, exist_ok=True)
    (docs / named.json).write_text(json.dumps(results, indent=2))
    where = "the object axis" if world == "native" else f"the object axis in world {world}"
    exams = list(dict.fromkeys(r.get("exam", EXAM) for r in results["rows"]))
    lines = [
        f"# Results: deconfounded data x low-rank update, {where}",
        "",
        f"Generated by `python -m train.experiment` ({', '.join(f'{k}={value(v)}' for k, v in s.items())}). "
        f"Training sets: {s['n']} oracle demonstrations each at {s['image_size']} px; the held-out exam has "
        f"{s['trials']} trials (task, a swap for every other object, occ, nonsense)"
        + (
            f"; the canonical exam is LIBERO's own initial states, {s['states']} per task, the same faces on each"
            if CANONICAL in exams
            else ""
        )
        + ". Rates carry k/n and a 95% interval that resamples whole trials (a trial's rollouts share its scene); "
        "chance for obeyed-name/true-target is 1 / (objects in the scene), and the `position` row is the measured "
        "shortcut on the same exam"
        + (
            "; the `named_place` row is the measured shortcut of a policy that reads the name only as where its object always "
            "stood in the confounded data, and the last column is obeyed name on the swaps `named_place` does not obey"
            if any(r.get("policy") == "named_place" for r in results["rows"])
            else ""
        )
        + ". Obeyed name is given at three levels: landed within 5 cm, within 2 cm, achieved "
        "the program on the named object.",
    ]
    for exam in exams:
        if len(exams) > 1:
            title = "the canonical exam (LIBERO's own initial states)" if exam == CANONICAL else "the deconfounded exam"
            lines += ["", f"## On {title}"]
        lines += _table([r for r in results["rows"] if r.get("exam", EXAM) == exam])
    if results.get("not_run"):
        lines += ["", f"Not run (no finished training in `{s['out']}`): {', '.join(results['not_run'])}."]
    trained = [r for r in results["rows"] if r["data"] and r.get("exam", EXAM) == EXAM]
    if trained:
        plot_curves(trained, docs / named.curves)
        if CANONICAL in exams:
            plot_faces([r for r in results["rows"] if r.get("exam") == CANONICAL], docs / named.faces)
            lines += ["", f"![faces on the canonical exam]({named.faces})"]
        lines += [
            "",
            f"![training curves]({named.curves})",
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
    (docs / named.results).write_text("\n".join(lines) + "\n")


SHORTCUT_LABELS = {"position": "`position` (shortcut)", "named_place": "`named_place` (the name as a place)"}


def _table(rows: list[dict]) -> list[str]:
    beyond = any("beyond_named_place" in r for r in rows)
    lines = [
        "",
        "| data | fine-tune | task | obeyed name (5 cm) | obeyed (2 cm) | obeyed (achieved) | grounded (first frame) "
        "| true target | occ | nonsense | chance |" + (" obeyed where `named_place` is not |" if beyond else ""),
        "|---|---|---|---|---|---|---|---|---|---|---|" + ("---|" if beyond else ""),
    ]
    for r in rows:
        f = r["faces"]
        levels = f["obeyed_name"].get("by_level") or {}
        by = [cell(levels[lv]) if lv in levels else "—" for lv in ("2cm", "achieved")]
        who = (r["data"], r["finetune"]) if r["data"] else ("—", SHORTCUT_LABELS[r["policy"]])
        grounded = cell(r["grounding"]) if "grounding" in r else "—"
        lines.append(
            f"| {who[0]} | {who[1]} | {cell(f['task'])} | {cell(f['obeyed_name'])} | {by[0]} | {by[1]} | {grounded} "
            f"| {cell(f['true_target'])} | {cell(f['occ'])} | {cell(f['nonsense'])} | {f['obeyed_name']['chance']:.0%} |"
            + (f" {cell(r['beyond_named_place']) if 'beyond_named_place' in r else '—'} |" if beyond else "")
        )
    return lines


def plot_faces(rows: list[dict], path: Path) -> None:
    """Each policy's faces (task, obeyed name, true target, occ, nonsense) side by side, with their
    trial-resampled intervals: a reading policy obeys, a blind one does the task and goes to the original."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    faces = ("task", "obeyed_name", "true_target", "occ", "nonsense")
    fig, ax = plt.subplots(figsize=(9, 3.6))
    width = 0.8 / max(1, len(rows))
    for i, r in enumerate(rows):
        label = f"{r['data']} {r['finetune']}" if r["data"] else SHORTCUT_LABELS[r["policy"]].replace("`", "")
        rates = [r["faces"][f]["rate"] for f in faces]
        lo, hi = zip(*((r["faces"][f].get("ci_trials") or r["faces"][f]["ci"]) for f in faces))
        x = np.arange(len(faces)) + (i - (len(rows) - 1) / 2) * width
        errors = [[max(0.0, v - a) for v, a in zip(rates, lo)], [max(0.0, b - v) for v, b in zip(rates, hi)]]
        ax.bar(x, rates, width, yerr=errors, capsize=2, label=label)
    ax.set_xticks(np.arange(len(faces)), [f.replace("_", " ") for f in faces])
    ax.set(ylim=(0, 1.05), ylabel="rate (95% CI, trials resampled)", title="on LIBERO's own initial states")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


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
    print((Path(options.docs) / names(options.world).results).read_text())


if __name__ == "__main__":
    sys.exit(main("python -m train.experiment", ExperimentOptions, experiment, doc=__doc__))
