"""Generation: the options -> one audited plan -> the product they ask for.

Every product starts from the same plan-and-audit step (gen/planning/plan.py) and one provenance record
(gen/products/provenance.py); then a builder makes it: a LeRobot dataset (gen/products/dataset.py), a plan alone
(`plan_only=true`, gen/products/plan_only.py) or an exam (`split=exam`, gen/products/exam.py).
"""

from __future__ import annotations

import time
from pathlib import Path

from gen.config import GenConfig, finished
from gen.planning.plan import plan_and_audit
from gen.products import dataset, exam, plan_only
from gen.products.provenance import Provenance

Summary = dataset.DatasetSummary | dataset.AlreadyComplete | plan_only.PlanSummary | exam.ExamSummary


def generate(cfg: GenConfig, progress: bool = True) -> Summary:
    started = time.perf_counter()
    out = Path(cfg.out or f"datasets/{cfg.referent}")
    if (generation := finished(cfg)) is not None:
        return dataset.already_complete(cfg, out, generation)
    planned = plan_and_audit(cfg)
    provenance = Provenance.of(cfg, [share.referent for share in planned.shares])
    if cfg.split == "exam":
        return exam.build(cfg, planned, provenance, out, started, progress)
    if cfg.plan_only:
        return plan_only.build(planned, provenance, out, started)
    return dataset.build(cfg, planned, provenance, out, started, progress)
