"""The release in LIBERO's scenes: one set of weights on the seven-type mix, every axis judged in
LIBERO's own simulator, beside the same mix laid out as LIBERO's demonstrations are.

python -m train.release                          # every stage; a killed run continues where it stopped
python -m train.release 'arms=[confounded]'      # one arm: two processes on one out= run the arms side by side
python -m train.release train=false              # nothing trained or taken: the docs from what is finished
python -m train.release 'arms=[]' 'favour=[goal]' # an axis that fell short: the deconfounded cool-down redone favouring it

Stages, each done once and reused (train/stages.py), so the run spans as many sittings as it needs:

* **data**, one dataset per arm, the README's seven-type mix (`per_type` episodes of each):
  `deconfounded`, and `confounded`: the same types laid out as LIBERO's demonstrations are where
  LIBERO has tasks of that kind (`confound=layout`: each grocery in the scene of LIBERO-Object's
  task that fetches it; the bowls in LIBERO-Spatial's tasks' pairs of places; LIBERO-Goal's one
  layout) and, for the four kinds LIBERO never asks (color, category, negation, composition), with
  the target always where LIBERO puts its targets (`confound=position`: the canonical slot, LIBERO's
  target region): what a LIBERO-like collection of those instructions would hold;
* **exams**: a held-out `split=exam` exam per axis (`trials`), and the canonical exams of
  LIBERO-Object, -Spatial and -Goal (`states` of LIBERO's own initial states per task);
* **training**: one LoRA per arm on its mix, docs/RESULTS_LIBERO.md's recipe (the tiny policy, the
  pointer loss), `steps_per_axis` steps per type, the last `cool` of them cooling the learning
  rate to `lr_floor`, every batch drawing the seven types equally (`balance`);
* **takes**: each arm on each axis's exam in our rebuild, with the `position` shortcut (and
  `named_place`, where a type has one) on the same rows; in LIBERO's simulator for the arms in
  `libero`; the deconfounded checkpoint on the canonical exams in LIBERO's simulator;
* **favoured** (`favour`, the fix tried once for axes that fall short): the deconfounded arm's
  cool-down redone from where it began (its `stable.pt`), the batches drawing the favoured axes'
  types `favour_share` of the time, and that checkpoint's takes in both simulators: the favoured
  axes first, then the others (one set of weights is judged on all seven).
  Where that state is gone (a new machine restores only the arm's final weights), the arm's
  constant-rate phase is trained again first (`deconfounded-stem`: the same data, seed and rates up
  to the cool-down's start) and the cool-down branches from its last state.

A run outlives its machine: on a new one, the committed results of the same out= and options are
carried (a take is not redone while the weights, or a reference policy's exam, it was taken with
are the same) and each arm's committed checkpoint restored with its log (its data then not
regenerated); `sims=[libero]` takes only LIBERO's simulator's exams.

Results (from the finished reports, whichever process finishes last): docs/RESULTS_LIBERO_AXES.md,
docs/results_libero_axes.json (rows: axis, arm, sim, faces) and docs/libero_axes.png; the
checkpoints in docs/checkpoints/libero-release-lora and docs/checkpoints/libero-release-confounded-lora.
"""

from __future__ import annotations

import json
import sys
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from core.exam import Exam, read
from eval.scoring.score import CARRY_STAGES
from gen.config import GenConfig
from gen.planning import mix
from jobs.cli import UserError, main
from referents import registry
from train.stages import (
    WEIGHTS_DIGEST,
    Commands,
    Ledger,
    begun_with,
    canonical_once,
    cell,
    commit,
    exam_report,
    finished_report,
    gen_command,
    generate_once,
    recipe,
    reference_digest,
    reference_report,
    restore,
    train_log,
    train_once,
    value,
    weights_digest,
)

if TYPE_CHECKING:
    from train.fit import TrainConfig

# axis -> (the mix's item: the type in its LIBERO scene, the confounded arm's confound)
AXES: dict[str, tuple[str, str]] = {
    "object": ("object@libero_object", "layout"),
    "relation": ("relation@libero_spatial", "layout"),
    "goal": ("goal@libero_goal", "layout"),
    "color": ("color@libero_spatial", "position"),
    "category": ("category@libero_object", "position"),
    "negation": ("negation@libero_object", "position"),
    "composition": ("composition@libero_object", "position"),
}
ARMS = ("deconfounded", "confounded")
FAVOURED = "favoured"  # the deconfounded arm with its cool-down redone favouring the axes in `favour`
STEM = "deconfounded-stem"  # the deconfounded arm's constant-rate phase alone, retrained where its stable.pt is gone
SIMS = ("ours", "libero")
CANONICAL = ("libero_object", "libero_spatial", "libero_goal")
COMMITTED = {"deconfounded": "libero-release-lora", "confounded": "libero-release-confounded-lora"}
# the checkpoint of the object axis alone, whose canonical task rate the release's stands beside
SINGLE_AXIS = "libero_object-deconfounded-lora"
RESULTS, JSON, PICTURE = "RESULTS_LIBERO_AXES.md", "results_libero_axes.json", "libero_axes.png"
RECORD = "release.json"  # in `out`: the options its results depend on, written by the invocation that began it
# The options the results depend on (not how many processes or threads made them, nor where).
DETERMINING = ("axes", "per_type", "trials", "states", "steps_per_axis", "cool", "lr_floor", "point_weight",
               "balance", "replan", "image_size", "seed")  # fmt: skip
SHOWN = ("task", "obeyed_name", "true_target", "occ", "nonsense", "switch_obeyed")


@dataclass
class ReleaseOptions:
    arms: list[str] = field(default_factory=lambda: list(ARMS))  # the arms this process trains and takes ([]: only favour's)
    axes: list[str] = field(default_factory=lambda: list(AXES))  # the types mixed (all seven: the release)
    per_type: int = 200  # episodes of each type in each arm's dataset
    trials: int = 20  # trials of each axis's held-out exam
    states: int = 2  # the canonical exams: LIBERO's initial states per task (drawn with seed + 1)
    steps_per_axis: int = 2000  # training steps per type (seven: 14000)
    cool: float = 1 / 3  # the last this fraction of the steps cools the learning rate down
    lr_floor: float = 0.05
    point_weight: float = 1.0  # the pointer loss, without which the tiny policy did not find LIBERO's groceries
    balance: bool = True  # every batch draws the types equally
    replan: int = 5  # actions of each predicted chunk executed before the policy looks again
    image_size: int = 128
    seed: int = 0  # the datasets' and the training's seed (the exams' is seed + 1)
    workers: int = 2  # generation and exam processes
    threads: int = 2  # training threads (1 each when the arms train side by side)
    libero: list[str] = field(default_factory=lambda: list(ARMS))  # arms whose exams LIBERO's simulator takes too
    sims: list[str] = field(default_factory=lambda: list(SIMS))  # the simulators this process takes exams in
    favour: list[str] = field(default_factory=list)  # axes that fell short: the deconfounded cool-down redone favouring them
    favour_share: float = 3 / 7  # the favoured axes' share of each batch in that cool-down (balanced, each has 1/7)
    canonical: bool = True  # the deconfounded checkpoint on LIBERO's canonical exams in LIBERO's simulator
    train: bool = True  # false: nothing made, trained or taken; the docs from what is finished
    commit_mb: float = 20.0  # checkpoints up to this size are copied to docs/checkpoints/
    out: str = "runs/release"
    docs: str = "docs"


def _check(options: ReleaseOptions) -> None:
    for name, allowed in (("arms", ARMS), ("axes", tuple(AXES)), ("libero", ARMS), ("sims", SIMS)):
        chosen = getattr(options, name)
        if any(c not in allowed for c in chosen) or len(set(chosen)) != len(chosen) or (name == "axes" and not chosen):
            raise UserError(f"{name} must be some of {', '.join(allowed)}, each once; got {chosen}")
    if not options.arms and not options.favour:
        raise UserError("arms=[] trains nothing unless favour names the axes whose cool-down to redo")
    if any(a not in options.axes for a in options.favour) or len(set(options.favour)) != len(options.favour):
        raise UserError(f"favour must name axes of the mix ({', '.join(options.axes)}), each once; got {options.favour}")
    if options.favour and (len(options.favour) == len(options.axes) or not 0 < options.favour_share < 1):
        raise UserError(f"favour must leave some axes out and favour_share lie in (0, 1); got {options.favour}, "
                        f"{options.favour_share}")  # fmt: skip
    if len(options.axes) < 2:
        raise UserError(f"axes must name two or more types to mix, got {options.axes}")
    for name in ("per_type", "trials", "states", "steps_per_axis", "replan", "workers", "threads"):
        if getattr(options, name) < 1:
            raise UserError(f"{name} must be at least 1, got {getattr(options, name)}")
    if options.states > 50:
        raise UserError(f"states must be at most 50 (LIBERO's initial states per task), got {options.states}")
    if not 0 <= options.cool < 1 or not 0 <= options.lr_floor <= 1 or options.point_weight < 0:
        raise UserError(f"cool must be in [0, 1), lr_floor in [0, 1], point_weight >= 0; got {options.cool}, "
                        f"{options.lr_floor}, {options.point_weight}")  # fmt: skip


def claim(options: ReleaseOptions, begin: bool) -> dict:
    """The determining options `out` was begun with (train/stages.py `claim`)."""
    wanted = {k: getattr(options, k) for k in DETERMINING}
    return begun_with(Path(options.out), wanted, RECORD, "release", "python -m train.release", begin)


def _stages(options: ReleaseOptions) -> dict[str, tuple[str, GenConfig]]:
    """Stage name -> (command, config): each chosen arm's dataset (the deconfounded one for `favour`
    too) and every axis's exam."""
    root, stages = Path(options.out), {}
    items = [AXES[a][0] for a in options.axes]
    needed = [*options.arms, *(["deconfounded"] if options.favour and "deconfounded" not in options.arms else [])]
    for arm in needed:  # the favoured cool-down trains on the deconfounded arm's data
        mixed = [f"referent=[{','.join(items)}]", f"n={options.per_type * len(items)}", f"seed={options.seed}"]
        if arm == "confounded":
            mixed.append(f"confound=[{','.join(AXES[a][1] for a in options.axes)}]")
        stages[f"data {arm}"] = gen_command(mixed, root / "data" / arm, options.image_size, options.workers)
    for axis in options.axes:
        type_, world = mix.split(AXES[axis][0])
        exam = (f"referent={type_}", f"world={world}", f"n={options.trials}", "split=exam", f"seed={options.seed + 1}")
        stages[f"exam {axis}"] = gen_command(exam, root / "exams" / axis, options.image_size, options.workers)
    return stages


def _canonical(options: ReleaseOptions, ledger: Ledger, commands: Commands) -> dict[str, tuple[Exam, Path]]:
    """LIBERO's canonical exams (gen.canonical), made once."""
    made = {}
    for world in CANONICAL:
        out = Path(options.out) / "exams" / f"canonical-{world}"
        canonical_once(world, options.states, options.seed + 1, options.image_size, out, ledger, f"generate canonical {world}",
                       commands)  # fmt: skip
        made[world] = (read(str(out)), out)
    return made


def _train(options: ReleaseOptions, arm: str, ledger: Ledger, commands: Commands) -> dict | None:
    """Train (or continue, or reuse) the arm's LoRA; its log."""
    cfg, line = _train_config(options, arm)
    commands.append(line)
    return train_once(cfg, ledger, f"train {arm}")


def _trained(options: ReleaseOptions, arm: str) -> bool:
    """Whether the arm's training is finished on this recipe (its data is then not needed)."""
    cfg, _ = _train_config(options, arm)
    log = train_log(Path(cfg.out))
    return log is not None and recipe(log["config"]) == recipe(asdict(cfg))


def _train_config(options: ReleaseOptions, arm: str) -> tuple[TrainConfig, str]:
    """The arm's training run and its command line. The favoured arm branches from the deconfounded
    arm's state where its cool-down began (`_branch`), on the same data; the stem is that arm's run
    up to there, at its constant rate."""
    from train.fit import LoraOptions, TrainConfig

    root = Path(options.out)
    steps = options.steps_per_axis * len(options.axes)
    decay = int(round(steps * options.cool))
    favoured, stem = arm == FAVOURED, arm == STEM
    cfg = TrainConfig(
        dataset=str(root / "data" / ("deconfounded" if favoured or stem else arm)),
        out=str(root / "ckpt" / arm),
        steps=steps - decay if stem else steps,
        decay=0 if stem else decay,
        lr_floor=1.0 if stem else options.lr_floor,
        lora=LoraOptions(16),
        point_weight=options.point_weight,
        balance=options.balance,
        favour=[recorded(a) for a in options.favour] if favoured else [],
        favour_share=options.favour_share,
        branch=str(_branch(root)) if favoured else "",
        threads=options.threads,
        seed=options.seed,
        resume=True,
    )
    fix = f" favour=[{','.join(cfg.favour)}] favour_share={cfg.favour_share:.4g} branch={cfg.branch}" if favoured else ""
    line = (
        f"python -m train dataset={cfg.dataset} policy=tiny lora.rank=16 steps={cfg.steps} decay={cfg.decay} "
        f"lr_floor={cfg.lr_floor} point_weight={cfg.point_weight} balance={str(cfg.balance).lower()}{fix} "
        f"threads={cfg.threads} seed={cfg.seed} out={cfg.out}"
    )
    return cfg, line


def _branch(root: Path) -> Path:
    """Where the favoured cool-down begins: the deconfounded arm's state at its cool-down's start
    where this machine trained that arm, else the stem's last state (the same step and rates)."""
    from train.fit import LAST, STABLE

    kept = root / "ckpt" / "deconfounded" / STABLE
    return kept if kept.is_file() else root / "ckpt" / STEM / LAST


def recorded(axis: str) -> str:
    """The referent type the axis's episodes record (LIBERO's own kinds of task by their suite's name)."""
    type_, world = mix.split(AXES[axis][0])
    return registry.load(type_, world=world).name


def _report_dir(root: Path, arm: str, exam: str, sim: str) -> Path:
    return root / "reports" / arm / f"{exam}-{sim}"


def run(options: ReleaseOptions, carried: dict) -> None:
    """Every stage the chosen arms need, in the order that gives results soonest: data, exams,
    then per arm its training and its takes in our rebuild, then LIBERO's simulator's takes; none
    that `carried` (`_carried`) holds for the same weights or exam is redone."""
    stages = _stages(options)
    from train.policy import MODEL_FILE

    root = Path(options.out)
    ledger, commands = Ledger(root), Commands(root)
    exams: dict[str, tuple[Exam, Path]] = {}
    for name, (line, cfg) in stages.items():
        kind, what = name.split()
        favouring = what == "deconfounded" and options.favour and not _trained(options, FAVOURED)
        again = kind == "data" and _trained(options, what)  # trained on it already (here or restored)
        if again and not favouring:
            continue  # the dataset is needed again only to retrain
        commands.append(line)
        generate_once(cfg, ledger, f"generate {name}" + (" again, for the favoured run" if again else ""))
        if kind == "exam":
            exams[what] = (read(str(cfg.out)), Path(str(cfg.out)))
    canonical = _canonical(options, ledger, commands) if options.canonical and "deconfounded" in options.arms else {}
    for axis, (exam, folder) in exams.items():
        type_, world = mix.split(AXES[axis][0])
        if registry.load(type_, world=world).code.named_place is not None and "ours" in options.sims:
            out = root / "reports" / "named_place" / axis
            commands.append(f"python -m eval policy=named_place exam={folder} workers=2 out={out}")
            if not _is_carried(carried, (axis, "axis", "named_place", "ours"), reference_digest(exam, "named_place")):
                reference_report(exam, "named_place", out, ledger, f"named_place {axis}")
    trained = {}
    for arm in options.arms:
        _train(options, arm, ledger, commands)
        trained[arm] = root / "ckpt" / arm
        commit(trained[arm] / MODEL_FILE, Path(options.docs) / "checkpoints" / COMMITTED[arm], options.commit_mb)
        _takes(options, arm, trained[arm], exams, "ours", ledger, commands, carried)
    if options.favour:
        if _branch(root).parent.name == STEM:
            _train(options, STEM, ledger, commands)
        _train(options, FAVOURED, ledger, commands)
        weights = root / "ckpt" / FAVOURED
        favoured = {a: exams[a] for a in options.favour}
        for chosen in (favoured, {a: e for a, e in exams.items() if a not in favoured}):  # what it was for, first
            for sim in SIMS:
                _takes(options, FAVOURED, weights, chosen, sim, ledger, commands, carried)
    for arm, weights in trained.items():
        if arm in options.libero:
            _takes(options, arm, weights, exams, "libero", ledger, commands, carried)
    if "deconfounded" in trained:
        named = {f"canonical-{world}": made for world, made in canonical.items()}
        _takes(options, "deconfounded", trained["deconfounded"], named, "libero", ledger, commands, carried, False)


def _takes(
    options: ReleaseOptions,
    arm: str,
    weights: Path,
    exams: dict[str, tuple[Exam, Path]],
    sim: str,
    ledger: Ledger,
    commands: Commands,
    carried: dict,
    baseline: bool = True,
) -> None:
    """The checkpoint's take of each exam in `sim` (ours: with the `position` shortcut's faces),
    unless these weights' take of it is among the committed results."""
    if sim not in options.sims:
        return
    digest = weights_digest(weights)
    for name, (exam, folder) in exams.items():
        out = _report_dir(Path(options.out), arm, name, sim)
        commands.append(
            f"python -m eval policy=ckpt:{weights} exam={folder} replan={options.replan} workers=2 sim={sim} out={out}"
        )
        if _is_carried(carried, (*_row_key(name), arm, sim), digest):
            continue
        stage = f"eval {arm} {name} {sim}"
        exam_report(exam, weights, exam.trials, out, options.replan, ledger, stage, baseline and sim == "ours", sim)


def _row_key(name: str) -> tuple[str, str]:
    """A take's exam folder name as its row's (axis, exam)."""
    return (name, "axis") if name in AXES else (name.removeprefix("canonical-"), "canonical")


def _carried(options: ReleaseOptions) -> dict:
    """The rows of the committed results (docs/results_libero_axes.json) when they are this run's
    (the same out= begun with the same options): a take outlives the machine that took it, and
    is kept while the weights (or, of a reference policy, the exam) it was taken with are the same."""
    path = Path(options.docs) / JSON
    try:
        committed = json.loads(path.read_text())
    except (OSError, ValueError):
        return {}
    same = committed.get("out") == options.out and committed.get("settings") == {k: getattr(options, k) for k in DETERMINING}
    return committed if same else {}


def _is_carried(carried: dict, key: tuple[str, str, str, str], digest: str | None) -> bool:
    return any(_key(r) == key and r.get("weights") == digest for r in carried.get("rows", []))


def _key(row: dict) -> tuple[str, str, str, str]:
    return row["axis"], row["exam"], row["arm"], row["sim"]


def collect(options: ReleaseOptions, carried: dict) -> dict:
    """Every finished result under `out`, whichever process took it, and the `carried` rows whose
    weights (or exam) are still the ones here: the rows the docs show (the options it was begun
    with, `claim`'s, are added by `release`)."""
    from jobs.partial import Partial

    root = Path(options.out)
    rows, not_run, training, digests = [], [], {}, {}
    for arm in (*ARMS, FAVOURED):
        weights = root / "ckpt" / arm
        log = train_log(weights)
        if log is None:
            if arm != FAVOURED:
                data = root / "data" / arm
                made = "" if (data / "meta").is_dir() else f" (its data: {len(Partial(data).saved())} episodes so far)"
                not_run.append(f"training {arm}{made}")
            elif options.favour:
                not_run.append(f"training {arm}")
            continue
        training[arm] = {"steps": log["steps"], "final_loss": log["final_loss"],
                         "loss_curve": [(h["step"], round(h["loss"], 5)) for h in log["history"]]}  # fmt: skip
        if log["config"].get("favour"):
            cfg = log["config"]
            favoured = [a for a in AXES if recorded(a) in cfg["favour"]]
            training[arm] |= {"favour": favoured, "favour_share": cfg["favour_share"], "branch": cfg["branch"]}
        digest = digests[arm] = weights_digest(weights)
        for name in [*AXES, *(f"canonical-{w}" for w in CANONICAL)]:
            for sim in SIMS:
                report = finished_report(_report_dir(root, arm, name, sim), digest)
                if report is None:
                    continue
                axis, exam = _row_key(name)
                rows.append({
                    "axis": axis, "exam": exam, "arm": arm, "sim": sim, "weights": digest, "faces": report["faces"],
                    "exam_digest": report.get("exam_digest"), "position": (report.get("baseline") or None),
                    "rollouts": report.get("rollouts"),
                    "reach_probe": report.get("reach_probe"), "per_object": report.get("per_object"),
                    "carry_probe": report.get("carry_probe"),
                    "simulator_versions": report.get("simulator_versions"),
                })  # fmt: skip
    for axis in AXES:
        folder = root / "reports" / "named_place" / axis
        if (report := finished_report(folder, None)) is not None:
            stamp = (folder / WEIGHTS_DIGEST).read_text()
            rows.append({"axis": axis, "exam": "axis", "arm": "named_place", "sim": "ours", "weights": stamp,
                         "faces": report["faces"], "exam_digest": report.get("exam_digest")})  # fmt: skip
        if (exam := root / "exams" / axis / "exam.json").is_file():
            digests[f"named_place {axis}"] = reference_digest(read(str(exam.parent)), "named_place")
    taken = {_key(r) for r in rows}
    for r in carried.get("rows", []):
        arm = r["arm"] if r["arm"] != "named_place" else f"named_place {r['axis']}"
        if _key(r) not in taken and r.get("weights") is not None and r.get("weights") == digests.get(arm):
            rows.append(r)
    return {
        "out": options.out,
        "libero_arms": options.libero,
        "confounded_arm": {axis: confound for axis, (_, confound) in AXES.items()},
        "rows": rows,
        "training": training,
        "not_run": not_run,
        "commands": list(dict.fromkeys([*carried.get("commands", []), *Commands(root).read()])),
        "timings_s": carried.get("timings_s", {}) | Ledger(root).spent,
    }


def _find(results: dict, axis: str, arm: str, sim: str, exam: str = "axis") -> dict | None:
    return next((r for r in results["rows"] if (r["axis"], r["arm"], r["sim"], r["exam"]) == (axis, arm, sim, exam)), None)


def write_docs(results: dict, docs: Path) -> None:
    docs.mkdir(parents=True, exist_ok=True)
    (docs / JSON).write_text(json.dumps(results, indent=2))
    s = results["settings"]
    lines = [
        "# Results: the seven axes in LIBERO's scenes, one set of weights",
        "",
        f"Generated by `python -m train.release` ({', '.join(f'{k}={value(v)}' for k, v in s.items())}: the options "
        f"`{results['out']}` was begun with) from the "
        "reports its takes wrote. Each arm's dataset holds "
        f"{s['per_type']} oracle demonstrations of each type at {s['image_size']} px; each axis's held-out exam "
        f"{s['trials']} trials. Rates are k/n with a 95% interval that resamples whole trials (rollouts of one "
        "trial share its scene). *ours*: our rebuild of LIBERO's scenes; *libero*: LIBERO's own simulator "
        "(`sim=libero`).",
        "",
        "**The arms.** *deconfounded*: the README's seven-type mix, every object target and distractor in "
        "every place. *confounded*: the same types, laid out as LIBERO's demonstrations are where LIBERO has "
        "tasks of that kind: `object` each grocery in the scene of the LIBERO-Object task that fetches it, "
        "`relation` the two bowls in the places of a LIBERO-Spatial task, `goal` LIBERO-Goal's one layout. "
        "LIBERO asks nothing by colour, category, negation or composition, so there the confounded arm puts "
        "the target where LIBERO puts its targets (`confound=position`: the canonical slot, LIBERO-Object's "
        "target region and LIBERO-Spatial's bowl between the plate and the ramekin): that is what those "
        "instructions would teach if collected as LIBERO collects its own, the target found by its place. "
        "In LIBERO-Goal's one layout every goal stands in every scene, so the layout holds no shortcut "
        "among a task's alternatives (its audit finds none); what it withholds is any scene but that one. "
        "A LIBERO-Spatial relation's words name a place of the table (next to the plate, on the cookie box), "
        "and the places never move: laid out as LIBERO lays them, each place is always paired with the same "
        "other, but the words still say where the bowl is. What the confounded arm can learn instead of the "
        "words is the pairing (`position` on the held-out exam, whose pairs differ); where it obeys above that, "
        "it reads the place the words name, which is the relation.",
    ]
    axis_rows = [a for a in AXES if any(r["axis"] == a and r["exam"] == "axis" for r in results["rows"])]
    if axis_rows:
        shown = _arms_taken(results)
        lines += [
            "",
            "## Obeyed name, per axis",
            "",
            "A swap row changes one word; *obeyed* is the hand within 5 cm of what the new word names.",
            "",
            "| axis | "
            + " | ".join(f"{arm}, {sim}" for arm in shown for sim in ("libero", "ours"))
            + " | `position` (ours) | `named_place` (ours) | chance |",
            "|---|---|---|---|" + "---|---|" * len(shown),
        ]
        for axis in axis_rows:
            cells = [_face(_find(results, axis, arm, sim), "obeyed_name") for arm in shown for sim in ("libero", "ours")]
            ours = _find(results, axis, "deconfounded", "ours") or _find(results, axis, "confounded", "ours")
            position = cell(ours["position"]["obeyed_name"]) if ours and ours.get("position") else "—"
            named = _face(_find(results, axis, "named_place", "ours"), "obeyed_name")
            chance = next((f"{r['faces']['obeyed_name']['chance']:.0%}" for r in results["rows"] if r["axis"] == axis), "—")
            lines.append(f"| {axis} | {' | '.join(cells)} | {position} | {named} | {chance} |")
        taken = any(r["arm"] in ARMS and r["exam"] == "axis" for r in results["rows"])
        lines += ["", f"![obeyed name per axis, both arms, in LIBERO's simulator]({PICTURE})", ""] if taken else [""]
        lines += ["## Every face", "", "| axis | arm | sim | " + " | ".join(SHOWN) + " |", "|---|---|---|" + "---|" * len(SHOWN)]
        for axis in axis_rows:
            for r in (x for x in results["rows"] if x["axis"] == axis and x["exam"] == "axis"):
                lines.append(f"| {axis} | {r['arm']} | {r['sim']} | " + " | ".join(_face(r, f) for f in SHOWN) + " |")
        if taken:  # the picture is of the arms: none taken yet, none drawn
            plot(results, docs / PICTURE)
    canonical = [r for r in results["rows"] if r["exam"] == "canonical"]
    if canonical:
        lines += [
            "",
            "## LIBERO's own tasks with seven axes in one weight",
            "",
            f"The deconfounded checkpoint on the canonical exams ({s['states']} of LIBERO's initial states per task), "
            "in LIBERO's simulator.",
            "",
            "| suite | task | obeyed name | true target |",
            "|---|---|---|---|",
        ]
        for r in canonical:
            lines.append(f"| {r['axis']} | {_face(r, 'task')} | {_face(r, 'obeyed_name')} | {_face(r, 'true_target')} |")
        single = _single_axis(docs)
        if single is not None:
            faces = " | ".join(cell(single["faces"][f]["libero"]) for f in ("task", "obeyed_name", "true_target"))
            lines += [
                "",
                f"Beside it, the single-axis checkpoint (`{SINGLE_AXIS}`, LIBERO-Object's object axis alone: "
                f"docs/RESULTS_LIBERO.md) on {single['exam']}, in LIBERO's simulator:",
                "",
                "| suite | task | obeyed name | true target |",
                "|---|---|---|---|",
                f"| libero_object | {faces} |",
            ]
    lines += _exams_taken(results)
    lines += _short_of(results)
    lines += _fix_tried(results)
    if results["training"]:
        lines += ["", "## Training", ""]
        for arm, t in results["training"].items():
            how = (f" (the deconfounded run from its cool-down's start, `{t['branch']}`, the batches drawing "
                   f"{', '.join(t['favour'])} {t['favour_share']:.0%} of the time)") if "favour" in t else ""  # fmt: skip
            lines.append(f"- {arm}: {t['steps']} steps{how}, final loss {t['final_loss']:.4f}")
    missing = list(results["not_run"]) + [
        f"{arm} on {axis} ({sim})"
        for arm, t in results["training"].items()
        for axis in s["axes"]
        for sim in ("ours", *(["libero"] if arm in results["libero_arms"] or arm == FAVOURED else []))
        if not _find(results, axis, arm, sim)
    ]
    if missing:
        lines += ["", f"Not finished in `{results['out']}` (yet): {', '.join(missing)}."]
    lines += ["", "Commands, in order:", "", "```", *results["commands"], "```", ""]
    lines += ["Wall time per stage (s, this 2-core machine, summed over the invocations that did its work):", ""]
    lines += [f"- {k}: {v}" for k, v in results["timings_s"].items()]
    (docs / RESULTS).write_text("\n".join(lines) + "\n")


def _exams_taken(results: dict) -> list[str]:
    """Which generation of an exam each row was taken on, where an exam's rows were not all taken
    on one: an exam regenerated on a machine of another numeric family (tests/sim/test_golden.py)
    has the same plan but other physics, so a take carried from one machine and a take made on
    another may stand in one table measured on different trials."""
    kept: dict[tuple[str, str], dict[str, list[str]]] = {}
    for r in results["rows"]:
        digest = (r.get("exam_digest") or "")[:8] or "not recorded"
        kept.setdefault((r["axis"], r["exam"]), {}).setdefault(digest, []).append(f"{r['arm']} {r['sim']}")
    mixed = {key: taken for key, taken in kept.items() if len(taken) > 1}
    if not mixed:
        return []
    lines = [
        "",
        "## Exams taken in more than one generation",
        "",
        "A row carried from an earlier machine was taken on the exam that machine generated; regenerated on a "
        "machine of another numeric family an exam keeps its plan (scenes, instructions, swaps) but not its "
        "physics (initial settling, horizons), so these rows were measured on different trials of one design "
        "(sha256 of the exam's files, first 8 hex digits; rows from before the digest was recorded: not recorded).",
        "",
        "| axis | exam | generation: rows |",
        "|---|---|---|",
    ]
    for (axis, exam), taken in mixed.items():
        generations = "; ".join(f"{digest}: {', '.join(rows)}" for digest, rows in sorted(taken.items()))
        lines.append(f"| {axis} | {exam} | {generations} |")
    return lines


def _short_of(results: dict) -> list[str]:
    """Why an axis falls short, from its takes: where each failed rollout's hand went (the reach
    probe: at what was asked for but not done, the grasp or the placing; at another object, the
    name not read; at neither, the reach itself), for a program that carries one thing to another
    the stage its failures stopped at (the carry probe), and the deconfounded arm's rates per
    asked-for value on the axes below 75% obeyed."""
    probed = [r for r in results["rows"] if r["exam"] == "axis" and r["arm"] != "confounded" and r.get("reach_probe")]
    if not probed:
        return []
    lines = [
        "",
        "## Where an axis falls short",
        "",
        "Each failed rollout by where the hand went (within 5 cm): at what was asked for (the name read, the "
        "grasp or placing failed), at another object (the name not read), or at neither (the reach failed).",
        "",
        "| axis | arm | sim | task | task failed: asked / other / neither | obeyed name | swap failed: named / other / neither |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in probed:
        where = ("reached_target", "went_distractor", "neither")
        task, swap = (" / ".join(str(r["reach_probe"].get(f, {}).get(k, 0)) for k in where) for f in ("task", "obeyed_name"))
        obeyed = _face(r, "obeyed_name")
        lines.append(f"| {r['axis']} | {r['arm']} | {r['sim']} | {_face(r, 'task')} | {task} | {obeyed} | {swap} |")
    carried = [r for r in probed if r.get("carry_probe")]
    if carried:
        lines += [
            "",
            "Where a program carries one thing to another (`put the bowl on the plate`), each failed rollout by the "
            "stage it stopped at: the hand took another thing it could carry (the carried thing's name not read), "
            "reached nothing, reached it and never lifted it (the grasp), or lifted it and did not bring it there.",
            "",
            "| axis | arm | sim | face | took another | reached nothing | not lifted | lifted, not brought |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for r in carried:
            for face, stages in r["carry_probe"].items():
                counts = " | ".join(str(stages[stage]) for stage in CARRY_STAGES)
                lines.append(f"| {r['axis']} | {r['arm']} | {r['sim']} | {face} | {counts} |")
    for r in probed:
        if r["arm"] != "deconfounded" or not r.get("per_object") or r["faces"]["obeyed_name"]["rate"] >= 0.75:
            continue
        lines += ["", f"{r['axis']}, deconfounded, {r['sim']}: per value asked for", ""]
        lines += ["| value | task | obeyed name |", "|---|---|---|"]
        for value_, f in sorted(r["per_object"].items()):
            rates = (cell(f[face]) if face in f else "—" for face in ("task", "obeyed_name"))
            lines.append(f"| {value_} | {' | '.join(rates)} |")
    return lines


def _fix_tried(results: dict) -> list[str]:
    """The favoured checkpoint beside the release, axis by axis, where both took the exam in one
    simulator: what the fix bought on the favoured axes and what it cost the others (one set of
    weights is judged on all seven)."""
    pairs = [
        (axis, sim, release, favoured)
        for axis in AXES
        for sim in SIMS
        if (release := _find(results, axis, "deconfounded", sim)) and (favoured := _find(results, axis, FAVOURED, sim))
    ]
    if not pairs:
        return []
    favour = results["training"].get(FAVOURED, {}).get("favour", [])
    lines = [
        "",
        "## The fix tried once, beside the release",
        "",
        f"The favoured checkpoint ({', '.join(favour) or 'no axis'} drawn more often in the cool-down) and the "
        "release checkpoint, on the axis's held-out exam in the same simulator (one design: where they took "
        "different generations of it, the table of generations above says so).",
        "",
        "| axis | sim | obeyed name: release | obeyed name: favoured | task: release | task: favoured |",
        "|---|---|---|---|---|---|",
    ]
    for axis, sim, release, favoured in pairs:
        cells = (_face(r, face) for face in ("obeyed_name", "task") for r in (release, favoured))
        lines.append(f"| {axis}{' (favoured)' if axis in favour else ''} | {sim} | {' | '.join(cells)} |")
    return lines


def _single_axis(docs: Path) -> dict | None:
    """The single-axis checkpoint's row on LIBERO-Object's canonical exam in LIBERO's simulator
    (docs/results_libero.json, scripts/libero_sim_results.py), if recorded."""
    path = docs / "results_libero.json"
    rows = json.loads(path.read_text()).get("libero_sim", {}).get("rows", []) if path.is_file() else []
    return next((r for r in rows if r["checkpoint"] == SINGLE_AXIS and r["exam_folder"] == "canonical"), None)


def _face(row: dict | None, face: str) -> str:
    return cell(row["faces"][face]) if row and face in row["faces"] else "—"


def _arms_taken(results: dict) -> tuple[str, ...]:
    """The columns of the per-axis table and the bars of its picture: both arms, and the favoured
    checkpoint once it has taken an exam."""
    return (*ARMS, *([FAVOURED] if any(r["arm"] == FAVOURED for r in results["rows"]) else []))


def plot(results: dict, path: Path) -> None:
    """Obeyed name per axis for both arms and the favoured checkpoint where it was taken (LIBERO's
    simulator where taken there, else ours, hatched), chance dotted and the `position` shortcut as a cross."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    axes = [a for a in AXES if any(r["axis"] == a and r["exam"] == "axis" for r in results["rows"])]
    x = np.arange(len(axes))
    fig, ax = plt.subplots(figsize=(1.3 * len(axes) + 4, 4))
    labelled: set[str] = set()
    colors = {"deconfounded": "tab:blue", "confounded": "tab:orange", FAVOURED: "tab:green"}
    drawn = [(arm, colors[arm]) for arm in _arms_taken(results)]
    width = 0.76 / len(drawn)
    for k, (arm, color) in enumerate(drawn):
        offset = (k - (len(drawn) - 1) / 2) * width
        for i, axis in enumerate(axes):
            row = _find(results, axis, arm, "libero") or _find(results, axis, arm, "ours")
            if row is None:
                continue
            face = row["faces"]["obeyed_name"]
            lo, hi = face.get("ci_trials") or face["ci"]
            label = f"{arm} (hatched: in ours)" if arm not in labelled else None
            labelled.add(arm)
            ax.bar(i + offset, face["rate"], width, color=color, hatch="" if row["sim"] == "libero" else "//",
                   yerr=[[face["rate"] - lo], [hi - face["rate"]]], capsize=3, label=label)  # fmt: skip
    for i, axis in enumerate(axes):
        row = next(r for r in results["rows"] if r["axis"] == axis and r["exam"] == "axis")
        ax.hlines(row["faces"]["obeyed_name"]["chance"], i - 0.45, i + 0.45, colors="k", linestyles=":")
        ours = _find(results, axis, "deconfounded", "ours") or _find(results, axis, "confounded", "ours")
        if ours and ours.get("position"):
            ax.plot(i, ours["position"]["obeyed_name"]["rate"], "kx", markersize=9, label="position shortcut" if i == 0 else None)
    ax.set_xticks(x, axes)
    ax.set(ylabel="obeyed name (5 cm)", ylim=(0, 1.05), title="Held-out exams; dotted: chance")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1))  # beside the bars, never over one
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def release(options: ReleaseOptions) -> None:
    _check(options)
    from train.policy import MODEL_FILE

    deconfounded = Path(options.out) / "ckpt" / "deconfounded"
    committed = Path(options.docs) / "checkpoints" / COMMITTED["deconfounded"] / MODEL_FILE
    untrained = train_log(deconfounded) is None and not committed.is_file()
    if options.train and options.favour and "deconfounded" not in options.arms and untrained:
        raise UserError(f"favour={options.favour} redoes the deconfounded arm's cool-down: train that arm first ({deconfounded})")
    begun = claim(options, begin=options.train)
    carried = _carried(options)  # read before the docs are rewritten
    if carried:  # the committed checkpoints of these results: their training outlives the machine
        for arm in ARMS:
            restore(Path(options.out) / "ckpt" / arm, Path(options.docs) / "checkpoints" / COMMITTED[arm])
    if options.train:
        run(options, carried)
    write_docs(collect(options, carried) | {"settings": begun}, Path(options.docs))
    print((Path(options.docs) / RESULTS).read_text())


if __name__ == "__main__":
    sys.exit(main("python -m train.release", ReleaseOptions, release, doc=__doc__))
