"""The dataset builder: an audited plan -> verified oracle demos -> a LeRobot v3.0 dataset.

Episodes are produced into a resumable partial folder beside `out` (jobs/partial.py), assembled
into the LeRobot files only once all exist, audited again as written, and moved to `out` in one
rename with `meta/generation.json` inside, so an interrupted run never leaves a half-written
dataset at `out` and never destroys the one that was there.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path

from core.products import AUDIT_PATH, GENERATION_PATH, PREVIEW_PATH
from core.spec import EpisodeSpec
from gen.config import GenConfig
from gen.planning import mix
from gen.planning.audit import agree, audit
from gen.planning.plan import Planned
from gen.products import card, scenes
from gen.products.provenance import Provenance, run_record
from gen.products.sheet import contact_sheet
from jobs import faults
from jobs.cli import UserError
from jobs.partial import Partial
from referents.registry import Referent


@dataclass
class DatasetSummary:
    out: Path
    episodes: int
    frames: int
    failed_attempts: int
    seconds: float
    verdict: str
    switched: int | None = None  # episodes that change course, of a set asked for some (`switched=`)

    def __str__(self) -> str:
        attempts = self.episodes + self.failed_attempts
        changed = "" if self.switched is None else f"{self.switched} of {self.episodes} episodes change course\n"
        return (
            f"wrote {self.episodes} episodes ({self.frames} frames) to {self.out}\n"
            f"oracle: {self.failed_attempts} failed demos resampled; success before retries "
            f"{self.episodes}/{attempts} = {self.episodes / attempts:.1%}\n"
            f"{changed}confound audit: {self.verdict}\n"
            f"wall time {self.seconds:.1f} s, {self.frames / self.seconds:.1f} frames/s, "
            f"{self.seconds / self.episodes:.2f} s/episode"
        )


@dataclass
class AlreadyComplete:
    out: Path
    episodes: int

    def __str__(self) -> str:
        return f"{self.out} is already complete ({self.episodes} episodes, same options); nothing to do"


def already_complete(cfg: GenConfig, out: Path, generation: dict) -> AlreadyComplete:
    """`resume=true` on a finished run (a requeued job that had in fact completed): a no-op when
    the options match, refused naming the first option that differs otherwise."""
    recorded, wanted = generation.get("run") or {}, run_record(cfg)
    changed = [k for k in wanted if recorded.get(k) != wanted[k]]
    if changed:
        name = "spec" if changed[0] == "spec_text" else changed[0]
        raise UserError(
            f"resume=true, but the complete dataset at out={out} was made with another {name} "
            f"({recorded.get(changed[0], 'unrecorded')!r}, not {wanted[changed[0]]!r}); pass overwrite=true to replace it"
        )
    return AlreadyComplete(out, generation["episodes"])


def audits(planned: Planned, written: list[EpisodeSpec] | None = None) -> list[tuple[Referent, dict]]:
    """Each referent type with its audits: of its plan and, given the written episodes, of its
    written ones, which must agree (resampled demos keep their roles)."""
    records = []
    for place, share in enumerate(planned.shares):
        record = {"planned": share.audit}
        if written is not None:
            record["written"] = audit(share.referent, mix.share(written, place, len(planned.shares)))
            record["agree"] = agree(record["planned"], record["written"])
            if not record["agree"]:
                raise RuntimeError("the audit of the written episodes disagrees with the plan's: resampling changed roles")
        records.append((share.referent, record))
    return records


def verdict(audited: list[tuple[Referent, dict]]) -> str:
    """The audits' verdict; a mix's (gen/planning/mix.py) names each type's."""
    if len(audited) == 1:
        return audited[0][1]["verdict"]
    return "; ".join(f"{referent.label}: {report['verdict']}" for referent, report in audited)


def write_audit(root: Path, records: list[tuple[Referent, dict]]) -> None:
    """`meta/audit.json`: the type's audits; a mix's, each type's under `referents`."""
    content = records[0][1] if len(records) == 1 else {"referents": {referent.label: record for referent, record in records}}
    (root / AUDIT_PATH).write_text(json.dumps(content, indent=2))


def write_generation(
    root: Path, provenance: Provenance, episodes: int, failed_attempts: int, seconds: float, switched: int | None = None
) -> None:
    """Written last: its presence marks the product complete."""
    record = provenance.generation(episodes, failed_attempts, seconds, switched)
    (root / GENERATION_PATH).write_text(json.dumps(record, indent=2, default=str))


def build(cfg: GenConfig, planned: Planned, provenance: Provenance, out: Path, started: float, progress: bool) -> DatasetSummary:
    with Partial(out) as partial:
        done = partial.start(run_record(cfg), cfg.resume, discard=cfg.overwrite)
        failed = _simulate(cfg, planned, partial, done, progress)
        root = partial.fresh_dataset()
        rows, frames, written = _assemble(cfg, planned, partial, root)
        records = audits(planned, written)
        audited = [(referent, record["written"]) for referent, record in records]
        scenes.write(root, rows)
        write_audit(root, records)
        contact_sheet(root, root / PREVIEW_PATH)
        seconds = time.perf_counter() - started
        switched = sum(spec.switch is not None for spec in written) if cfg.switched else None
        summary = DatasetSummary(out, len(rows), frames, failed, seconds, verdict(audited), switched)
        contents = card.dataset_contents(summary.episodes, summary.frames, failed, cfg.fps, planned.recording.interface)
        card.write(root, audited, provenance, contents)
        faults.point("finalize")
        write_generation(root, provenance, summary.episodes, failed, seconds, switched)
        partial.publish()
    return summary


def _simulate(cfg: GenConfig, planned: Planned, partial: Partial, done: int, progress: bool) -> int:
    """Produce every episode not yet in the partial run; returns the failed oracle attempts."""
    from tqdm import tqdm

    from gen.products.produce import DemoFailed
    from gen.products.workers import Job, WorkerCrash, produce

    shares = zip(cfg.shares(), planned.shares, strict=True)
    types = tuple((one.referent, one.spec_overrides(), share.setup) for one, share in shares)
    job = Job(types, cfg.spec, cfg.codec, cfg.seed, cfg.max_attempts)
    name = mix.name([share.referent.label for share in planned.shares])
    bar = tqdm(total=len(planned.designs), initial=done, desc=name, unit="ep", disable=not progress, dynamic_ncols=True)
    failed = 0
    try:
        for index, produced in enumerate(produce(job, planned.designs, cfg.workers or 1, cfg.backend, start=done), start=done):
            faults.point(f"episode:{index}")
            partial.save(index, produced)
            failed += len(produced.failures)
            bar.update()
            bar.set_postfix(retries=failed)
    except DemoFailed as exc:
        raise UserError(f"{exc}; the referent spec may place objects out of reach") from None
    except WorkerCrash as exc:
        raise UserError(str(exc)) from None
    finally:
        bar.close()
    return failed


def _assemble(cfg: GenConfig, planned: Planned, partial: Partial, root: Path) -> tuple[list[dict], int, list[EpisodeSpec]]:
    """The LeRobot files, from the episode files, in order."""
    from gen.lerobot.writer import LeRobotWriter, Recording

    setup, features = planned.recording, planned.recording.interface
    writer = LeRobotWriter(
        root, Recording(setup.fps, setup.image_size, setup.cameras, features.state_names, features.action_names, cfg.codec)
    )
    rows, written = [], []
    mixed, switched = len(planned.shares) > 1, planned.switched
    for produced in partial.episodes(cfg.n):
        rows.append(scenes.row(writer.add(produced.episode), produced.spec, produced, mixed, switched))
        written.append(produced.spec)
        faults.point(f"assemble:{len(rows) - 1}")
    writer.finalize()
    return rows, writer.frames, written
