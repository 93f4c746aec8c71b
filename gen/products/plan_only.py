"""The plan builder (`plan_only=true`): the audited plan's scene records, audit and card, with
nothing simulated — a 10,000-episode design checked in seconds before any compute is spent."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from gen.planning.plan import Planned
from gen.products import card, scenes
from gen.products.dataset import audits, verdict, write_audit, write_generation
from gen.products.provenance import Provenance
from jobs.partial import staging


@dataclass
class PlanSummary:
    out: Path
    episodes: int
    seconds: float
    verdict: str

    def __str__(self) -> str:
        return (
            f"planned {self.episodes} episodes to {self.out} (nothing simulated) in {self.seconds:.1f} s\n"
            f"confound audit: {self.verdict}"
        )


def build(planned: Planned, provenance: Provenance, out: Path, started: float) -> PlanSummary:
    with staging(out) as root:
        (root / "meta").mkdir(parents=True)
        mixed = len(planned.shares) > 1
        scenes.write(root, [scenes.row(i, spec, None, mixed, planned.switched) for i, spec in enumerate(planned.specs)])
        records = audits(planned)
        write_audit(root, records)
        audited = [(referent, record["planned"]) for referent, record in records]
        seconds = time.perf_counter() - started
        summary = PlanSummary(out, len(planned.specs), seconds, verdict(audited))
        card.write(root, audited, provenance, card.plan_contents(summary.episodes))
        write_generation(root, provenance, summary.episodes, 0, seconds)
    return summary
