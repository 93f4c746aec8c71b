"""`python -m eval.agreement`: it compares a take in our simulator with one in LIBERO's only when
they are what they claim (which simulator, which policy, which exam, two folders), and it never
replaces a file at `out=` it was not allowed to, nor fails after the figures on an `out=` it could
have refused first.

LIBERO's simulator is not needed: the `libero` take is a copy of a take in ours (the `nothing`
policy on a 2-trial exam) whose rollouts.parquet metadata key `deconfound.sim` (eval/sims/log.py
SIM_KEY) is rewritten to `libero`, which is exactly what a real `sim=libero` take writes there."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from core.exam import read
from eval.policies.registry import make
from eval.scoring.baseline import exam_digest
from eval.scoring.battery import take
from helpers import SMALL_EXAM, Shared
from jobs.cli import main

# rollouts.parquet's metadata keys (eval/sims/log.py SIM_KEY, POLICY_KEY, EXAM_KEY), spelt out so that
# this file also runs against code from before the exam's digest was recorded
SIM, POLICY, EXAM = b"deconfound.sim", b"deconfound.policy", b"deconfound.exam"


def retag(folder: Path, **changes: str | None) -> None:
    """Rewrite a take's rollouts.parquet metadata (None removes a key) and its report.json's fields alike."""
    keys = {"sim": (SIM, "simulator"), "policy": (POLICY, "policy"), "exam": (EXAM, "exam_digest")}
    path = folder / "rollouts.parquet"
    table = pq.read_table(path)
    meta = dict(table.schema.metadata or {})
    report = json.loads((folder / "report.json").read_text())
    for name, value in changes.items():
        key, field = keys[name]
        if value is None:
            meta.pop(key, None)
            report.pop(field, None)
        else:
            meta[key] = value.encode()
            report[field] = value
    pq.write_table(table.replace_schema_metadata(meta), path)
    (folder / "report.json").write_text(json.dumps(report))


@pytest.fixture(scope="module")
def takes(shared: Shared, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A 2-trial exam; `nothing`'s take of it in our simulator (`ours`), the same take relabelled as
    one in LIBERO's (`libero`), and a copy of the exam whose exam.json differs (`other`: another exam
    with the very same rows)."""
    root = tmp_path_factory.mktemp("agreement")
    exam = shared.dataset("object-exam", "referent=object", *SMALL_EXAM)
    take(read(exam), read(exam).trials, make("nothing"), root / "ours", baseline=False)
    shutil.copytree(root / "ours", root / "libero")
    retag(root / "libero", sim="libero")
    shutil.copytree(exam, root / "other")
    meta = json.loads((root / "other" / "exam.json").read_text())
    (root / "other" / "exam.json").write_text(json.dumps({**meta, "note": "another exam, the same rows"}))
    return {"exam": exam, "ours": root / "ours", "libero": root / "libero", "other": root / "other", "root": root}


def agreement(capsys: pytest.CaptureFixture, **options: object) -> tuple[int, str, list[str]]:
    """Run the command in this process: (exit code, stdout, stderr's lines)."""
    argv = [f"{k}={str(v).lower() if isinstance(v, bool) else v}" for k, v in options.items()]
    from eval.agreement import AgreementOptions, run

    code = main("python -m eval.agreement", AgreementOptions, run, argv)
    out, err = capsys.readouterr()
    return code, out, err.strip().splitlines()


def refused(code: int, err: list[str], *needles: str) -> None:
    assert code == 2 and len(err) == 1 and err[0].startswith("error: "), (code, err)
    assert all(n in err[0] for n in needles), err[0]


def test_a_take_records_which_exam_it_took(takes: dict[str, Path]) -> None:
    digest = exam_digest(read(takes["exam"]))
    assert pq.read_schema(takes["ours"] / "rollouts.parquet").metadata[EXAM] == digest.encode()
    assert json.loads((takes["ours"] / "report.json").read_text())["exam_digest"] == digest


def test_the_takes_agree_with_themselves_when_given_rightly(takes: dict[str, Path], capsys, tmp_path: Path) -> None:
    out = tmp_path / "agreement.json"
    code, printed, err = agreement(capsys, exam=takes["exam"], ours=takes["ours"], libero=takes["libero"], out=out)
    assert code == 0 and not err, err
    assert "nothing on" in printed and json.loads(out.read_text())["paired"]["swap"]["rate"] == 1.0


def test_an_existing_out_is_replaced_only_with_overwrite(takes: dict[str, Path], capsys, tmp_path: Path) -> None:
    """2a: out= used to replace any file silently (a take's report.md became JSON)."""
    kept = tmp_path / "notes.json"
    kept.write_text("mine")
    code, _, err = agreement(capsys, exam=takes["exam"], ours=takes["ours"], libero=takes["libero"], out=kept)
    refused(code, err, "already exists", "overwrite=true")
    assert kept.read_text() == "mine"
    report = takes["ours"] / "report.md"
    before = report.read_text()
    for overwrite in (False, True):  # a take's own files, not even with overwrite
        code, _, err = agreement(
            capsys, exam=takes["exam"], ours=takes["ours"], libero=takes["libero"], out=report, overwrite=overwrite
        )
        assert code == 2 and len(err) == 1, err
    assert report.read_text() == before
    code, _, err = agreement(capsys, exam=takes["exam"], ours=takes["ours"], libero=takes["libero"], out=kept, overwrite=True)
    assert code == 0 and json.loads(kept.read_text())["policy"] == "nothing"


def test_swapped_takes_are_refused(takes: dict[str, Path], capsys) -> None:
    """2b: ours= and libero= the wrong way round printed LIBERO's take under "ours"."""
    code, printed, err = agreement(capsys, exam=takes["exam"], ours=takes["libero"], libero=takes["ours"])
    refused(code, err, "swapped")
    assert not printed


def test_the_same_take_twice_is_refused(takes: dict[str, Path], capsys) -> None:
    """2b: the same folder twice reported 100% agreement."""
    for folder in ("ours", "libero"):
        code, printed, err = agreement(capsys, exam=takes["exam"], ours=takes[folder], libero=takes[folder])
        refused(code, err)
        assert not printed


def test_a_take_of_another_exam_is_refused(takes: dict[str, Path], capsys) -> None:
    """2b: an exam whose rows match the takes' but which is another exam was accepted."""
    code, printed, err = agreement(capsys, exam=takes["other"], ours=takes["ours"], libero=takes["libero"])
    refused(code, err, "another exam")
    assert not printed


def test_takes_by_two_policies_are_refused(takes: dict[str, Path], capsys, tmp_path: Path) -> None:
    shutil.copytree(takes["libero"], tmp_path / "random")
    retag(tmp_path / "random", policy="random")
    code, printed, err = agreement(capsys, exam=takes["exam"], ours=takes["ours"], libero=tmp_path / "random")
    refused(code, err, "different policies")
    assert not printed


def test_a_take_from_before_the_exam_digest_is_compared_with_a_warning(takes: dict[str, Path], capsys, tmp_path) -> None:
    """Takes written before `deconfound.exam` existed record no exam: compared (their rows' initial
    states are checked against the exam's), with a warning per take saying only a retake proves it."""
    for name in ("ours", "libero"):
        shutil.copytree(takes[name], tmp_path / name)
        retag(tmp_path / name, exam=None)
    code, printed, err = agreement(capsys, exam=takes["exam"], ours=tmp_path / "ours", libero=tmp_path / "libero")
    assert code == 0 and "nothing on" in printed
    assert len(err) == 2 and all(line.startswith("warning: ") and "retake" in line for line in err), err


def test_out_is_checked_before_anything_is_computed(takes: dict[str, Path], capsys, tmp_path: Path, monkeypatch) -> None:
    """2c: out= a folder, or under a file, ended in a traceback after the figures; a missing parent is made."""
    import eval.agreement

    def computed(*args: object) -> None:
        raise AssertionError("computed before out= was checked")

    monkeypatch.setattr(eval.agreement, "compare", computed)
    (tmp_path / "a-file").write_text("x")
    for out in (tmp_path, tmp_path / "a-file" / "agreement.json"):
        code, printed, err = agreement(capsys, exam=takes["exam"], ours=takes["ours"], libero=takes["libero"], out=out)
        refused(code, err, f"out={out}")
        assert not printed
    monkeypatch.undo()
    out = tmp_path / "missing" / "parent" / "agreement.json"
    code, _, err = agreement(capsys, exam=takes["exam"], ours=takes["ours"], libero=takes["libero"], out=out)
    assert code == 0 and json.loads(out.read_text())["policy"] == "nothing", err
