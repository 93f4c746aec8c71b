"""A policy through several LIBERO suites, LIBERO-PRO's perturbations among them, in one report.

python -m eval.suites policy=position 'suites=[libero_object,libero_object_swap,libero_object_lan]' states=5
python -m eval.suites policy=<yours> suites=all world=libero_object states=5

Each suite's canonical exam (python -m gen.canonical suite=<name>: LIBERO's own initial states of
that suite, its objects built into the scene, the perturbed instruction delivered) is made once in
`exams` (reused while its options are the same), the policy takes each (python -m eval, kept
rollouts and all: a killed run continues with resume=true), and `out` gets one report: a row
per suite with its task rate, obeyed name, true target, occ, nonsense and switch obeyed (a dash
where its exam has no such rows: `switches=0`), each with k/n and the
interval that resamples trials (report.json, report.md), and a picture with one bar group per
suite (suites.png). `suites=all` takes every suite of `world` whose files are installed and
whose tasks our skills can do (docs/LIBERO.md lists them, and why the others are not).
"""

from __future__ import annotations

import json
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

import oracle  # noqa: F401  (headless-rendering defaults before mujoco loads)
from core import libero
from core.exam import read
from core.spec import FAST
from eval.policies import FeatureMismatch, PolicyError
from eval.policies.registry import make
from gen.products.canonical import CanonicalOptions, build, suites_of, world_suite
from jobs.cli import UserError, main

FACES = ("task", "obeyed_name", "true_target", "occ", "nonsense", "switch_obeyed")
PICTURE = "suites.png"


@dataclass
class SuitesOptions:
    policy: str  # oracle, position, named_place, nothing, random, remote:HOST:PORT, lerobot:PATH, ckpt:PATH (eval/policies/)
    suites: list[str] = field(default_factory=lambda: ["all"])  # suite names, or [all]: every covered suite of `world`
    world: str = "libero_object"  # the LIBERO world whose suites `all` means (libero_10: LIBERO-10's, across its worlds)
    states: int = 5  # LIBERO's initial states per task in each exam (drawn with seed)
    tasks: int | None = None  # only each suite's first this many covered tasks (a quick look); default all
    seed: int = 0
    image_size: int = 256  # the exams' frames (the policy's side)
    switches: int = 1  # switch rows per trial in each exam (the instruction changed mid-course); 0: none
    look: str = FAST  # fast | full: how the exams' cameras draw (core/spec.py LOOKS)
    exams: str = "datasets/suites"  # where each suite's canonical exam is made, or found
    out: str | None = None  # the report; default runs/suites/<policy>
    workers: int = 1  # processes running rollouts
    resume: bool = False  # continue an interrupted run (each suite's take keeps its rollouts)
    overwrite: bool = False  # replace the reports at `out` and discard interrupted takes


def chosen(options: SuitesOptions) -> list[str]:
    """The suites named, `all` expanded to the world's covered ones; each checked (one line each)."""
    if options.suites == ["all"]:
        names = []
        for name in libero.suites(world_suite(options.world)):
            try:
                suites_of(CanonicalOptions(suite=name))
                names.append(name)
            except UserError:  # a suite nothing of which we can do
                continue
        if not names:
            raise UserError(f"no suite of world {options.world} has a task our skills and LIBERO's installed models can do")
        return names
    if not options.suites or len(set(options.suites)) != len(options.suites):
        raise UserError(f"suites must name suites once each (or be [all]), got {options.suites}")
    for name in options.suites:
        suites_of(CanonicalOptions(suite=name))
    return list(options.suites)


def _exam(options: SuitesOptions, suite: str) -> Path:
    """The suite's canonical exam in `exams`: made unless one of the same options is there."""
    some = f"-t{options.tasks}" if options.tasks else ""
    some += f"-{options.look}" if options.look != FAST else ""
    some += f"-sw{options.switches}" if options.switches != 1 else ""
    folder = Path(options.exams) / f"{suite}-s{options.states}-seed{options.seed}-{options.image_size}px{some}"
    made = CanonicalOptions(
        states=options.states,
        seed=options.seed,
        image_size=options.image_size,
        out=str(folder),
        suite=suite,
        tasks=options.tasks,
        look=options.look,
        switches=options.switches,
    )
    if not (folder / "exam.json").is_file():
        build(made)
    return folder


def run(options: SuitesOptions) -> None:
    if options.workers < 1:
        raise UserError(f"workers must be at least 1, got {options.workers}")
    names = chosen(options)
    from eval.__main__ import check_out
    from eval.scoring.battery import take

    out = Path(options.out or Path("runs") / "suites" / re.sub(r"[^A-Za-z0-9_.-]+", "_", options.policy))
    for name in names:
        check_out(out / name, options.overwrite or options.resume)
    try:
        policy = make(options.policy)
    except PolicyError as exc:
        raise UserError(str(exc)) from None
    rows = []
    for name in names:
        exam = read(_exam(options, name))
        try:
            report, _ = take(
                exam, exam.trials, policy, out / name, options.workers, options.policy, baseline=False,
                resume=options.resume, discard=options.overwrite,
            )  # fmt: skip
        except FeatureMismatch as exc:
            raise UserError(str(exc)) from None
        rows.append(suite_row(name, report))
        print(f"{name}: " + ", ".join(f"{f} {_short(rows[-1]['faces'][f])}" for f in FACES))
    (out / "report.json").write_text(json.dumps({"policy": options.policy, "suites": rows}, indent=2))
    (out / "report.md").write_text(table(options.policy, rows))
    picture(options.policy, rows, out / PICTURE)
    print(f"wrote {out}/report.json, report.md, {PICTURE}")


EMPTY = {"k": 0, "n": 0, "rate": None, "ci": [0.0, 1.0], "ci_trials": [0.0, 1.0]}  # a face the suite has no rows for


def suite_row(name: str, report: dict) -> dict:
    """A suite's row of the summary: each face, or an empty one where its exam has no such rows (a
    `_task` suite whose every swap is left out: exam.json says why)."""
    return {"suite": name, "exam": report["exam"], "faces": {f: report["faces"].get(f, EMPTY) for f in FACES}}


def _short(face: dict) -> str:
    return f"{face['rate']:.0%}" if face["n"] else "— (no rows)"


def _cell(face: dict) -> str:
    lo, hi = face.get("ci_trials") or face["ci"]
    return f"{face['rate']:.0%} ({face['k']}/{face['n']}; {lo:.0%}–{hi:.0%})" if face["n"] else "—"


def table(policy: str, rows: list[dict]) -> str:
    """One row per suite: each face with k/n and its trial-resampled 95% interval."""
    lines = [
        f"# `{policy}` across LIBERO's suites",
        "",
        "| suite | task | obeyed name | true target | occ | nonsense | switch obeyed |",
        "|---|---|---|---|---|---|---|",
    ]
    lines += [f"| {r['suite']} | " + " | ".join(_cell(r["faces"][f]) for f in FACES) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def picture(policy: str, rows: list[dict], path: Path) -> None:
    """One bar group per suite (the faces, with their intervals)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fig, ax = plt.subplots(figsize=(max(6.0, 1.1 * len(rows) + 2), 3.8))
    width = 0.8 / len(FACES)
    for i, face in enumerate(FACES):
        rates = [r["faces"][face]["rate"] or 0.0 for r in rows]
        bounds = [r["faces"][face].get("ci_trials") or r["faces"][face]["ci"] for r in rows]
        shown = [r["faces"][face]["n"] > 0 for r in rows]
        below = [max(0.0, v - lo) * s for v, (lo, _), s in zip(rates, bounds, shown)]
        errors = [below, [max(0.0, hi - v) * s for v, (_, hi), s in zip(rates, bounds, shown)]]
        ax.bar(np.arange(len(rows)) + (i - (len(FACES) - 1) / 2) * width, rates, width, yerr=errors, capsize=1.5,
               label=face.replace("_", " "))  # fmt: skip
    ax.set_xticks(np.arange(len(rows)), [r["suite"].removeprefix("libero_") for r in rows], rotation=30, ha="right", fontsize=8)
    ax.set(ylim=(0, 1.05), ylabel="rate (95% CI, trials resampled)", title=f"{policy} on LIBERO's and LIBERO-PRO's suites")
    ax.legend(fontsize=7, ncol=5, loc="upper center", bbox_to_anchor=(0.5, -0.32))
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main("python -m eval.suites", SuitesOptions, run, doc=__doc__))
