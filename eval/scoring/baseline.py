"""The measured shortcut baseline, kept per exam: the `position` reference policy's faces.

"Chance = 1/k" fits a policy that lands on a random object; the shortcut a confounded policy
learns (reach the canonical slot) scores what it scores on a given exam, so every report shows
that measured rate beside its own. It is measured once per exam and set of rollouts
(eval/scoring/battery.py) and cached here, where the offline scorer finds it too.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from pathlib import Path

from core import __version__, cache_dir
from core.exam import Exam
from core.products import ANSWERS_FILE, TRIALS_FILE

SHORTCUT = "position"  # the reference policy whose rates are the shortcut baseline


REPORT_VERSION = 2  # of eval/scoring/score.py's report: a baseline scored by another version is not reused


def exam_digest(exam: Exam, salt: str = "") -> str:
    """sha256 of `salt` and the exam's files: what a result was measured on, whatever folder holds the exam."""
    digest = hashlib.sha256(salt.encode())
    for name in ("exam.json", TRIALS_FILE, ANSWERS_FILE):
        digest.update((exam.root / name).read_bytes())
    return digest.hexdigest()


def _file(exam: Exam, rows: Sequence[int]) -> Path:
    key = exam_digest(exam, f"{__version__}/{REPORT_VERSION}/{sorted(int(r) for r in rows)}")
    return cache_dir() / "baselines" / f"{key[:24]}.json"


def cached_baseline(exam: Exam, rows: Sequence[int]) -> dict | None:
    """The shortcut's faces on the rollouts `rows` (their row numbers) of `exam`, if measured before."""
    try:
        return json.loads(_file(exam, rows).read_text())
    except (OSError, ValueError):
        return None


def store_baseline(exam: Exam, rows: Sequence[int], faces: dict) -> None:
    path = _file(exam, rows)
    try:  # the cache only saves time
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps(faces))
        tmp.replace(path)
    except OSError:
        pass
