"""Issue 49's small defects, each pinned by a test (the ones that need a generated exam are in
tests/sim/test_small_defects_exams.py): a broken `.venv-libero` is refused before a take starts, a
refused resume names what changed, `python -m eval` does not write into a product, an empty `out=`
is refused, the exam hint can be pasted into a shell, the README's commands run from the venv,
RESULTS_FACES.md's commands make its tables' rows, and a missing path is said to be missing."""

from __future__ import annotations

import dataclasses
import importlib
import json
import re
import shlex
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from jobs.cli import UserError, compose_config, main

ROOT = Path(__file__).resolve().parents[2]


def _one_line(capsys: pytest.CaptureFixture[str]) -> str:
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), lines
    return lines[0].removeprefix("error: ")


# --- 1. a .venv-libero without its packages -------------------------------------------------------


@pytest.fixture(scope="module")
def bare_python(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The python of a virtual environment with no packages, as an interrupted `make setup` leaves one."""
    venv = tmp_path_factory.mktemp("libero") / ".venv-libero"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    return venv / "bin" / "python"


def test_a_libero_environment_without_its_packages_is_refused_by_the_check(
    bare_python: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from eval.sims import libero as libero_sim

    monkeypatch.setattr(libero_sim, "PYTHON", bare_python)
    exam = SimpleNamespace(meta={"world": "libero_object"})
    with pytest.raises(libero_sim.SimUnavailable) as refused:
        libero_sim.check(exam, "nothing")  # type: ignore[arg-type]
    message = str(refused.value)
    assert "\n" not in message and "make setup" in message, message
    assert "libero" in message.split("(", 1)[1] and "numpy" in message, message  # names what is missing
    (bare_python.parents[1] / ".installed-mujoco-3.17.0").write_text("")  # a stamp make setup trusts: remove it
    with pytest.raises(libero_sim.SimUnavailable, match=r"rm -rf .*\.venv-libero && make setup"):
        libero_sim.check(exam, "nothing")  # type: ignore[arg-type]


# --- 2. a refused resume names the options -----------------------------------------------------------


def test_a_refused_resume_names_each_option_that_differs_with_what_it_was_and_is(tmp_path: Path) -> None:
    from jobs.partial import Partial

    before = {"n": 6, "seed": 0, "switches": 1, "options": {"keys": "libero", "replan": 5}, "rows": list(range(10))}
    with Partial(tmp_path / "ds") as partial:
        partial.start(before, resume=False)
    now = {"n": 6, "seed": 0, "options": {"keys": "libero", "replan": 8}, "rows": list(range(12)), "world": "libero_object"}
    with Partial(tmp_path / "ds") as partial, pytest.raises(UserError) as refused:
        partial.start(now, resume=True)
    message = str(refused.value)
    assert "\n" not in message and "()" not in message, message
    for said in (
        "switches was 1, now unset",  # only in the interrupted run's record
        'world was unset, now "libero_object"',  # only in this run's
        "options.replan was 5, now 8",  # a nested difference
        "rows was [0, 1, ..., 9] (10 items), now [0, 1, ..., 11] (12 items)",
    ):
        assert said in message, message
    assert "seed" not in message and "keys" not in message, message
    with Partial(tmp_path / "ds") as partial:  # the same options still resume
        assert partial.start(before, resume=True) == 0


# --- 3. python -m eval out=<a product> -----------------------------------------------------------------


def _product(folder: Path, kind: str) -> Path:
    """A folder as this project writes `kind`, down to the files `jobs.output.product_in` reads."""
    from core.exam import EXAM_FORMAT

    (folder / "meta").mkdir(parents=True)
    if kind == "exam":
        (folder / "exam.json").write_text(json.dumps({"format": EXAM_FORMAT}))
        return folder
    (folder / "meta" / "generation.json").write_text(json.dumps({"generator": "deconfound", "plan_only": kind == "plan"}))
    if kind == "export":
        (folder / "meta" / "info.json").write_text(json.dumps({"codebase_version": "v2.1"}))
    return folder


@pytest.mark.parametrize("kind", ["dataset", "plan", "exam", "export"])
@pytest.mark.parametrize("overwrite", [False, True])
def test_eval_and_score_refuse_to_write_a_report_into_a_product(tmp_path: Path, kind: str, overwrite: bool) -> None:
    from eval.__main__ import check_out
    from eval.scoring.report import check_out as check_report_out

    folder = _product(tmp_path / kind, kind)
    before = sorted(p.relative_to(folder) for p in folder.rglob("*"))
    for check in (check_out, check_report_out):  # python -m eval, and python -m eval.score
        with pytest.raises(UserError, match=rf"out={folder} is an? {kind} made here, not a report folder"):
            check(folder, overwrite)
    assert sorted(p.relative_to(folder) for p in folder.rglob("*")) == before
    check_out(tmp_path / "report", overwrite)  # a report folder is still taken


# --- 4. an empty out= ---------------------------------------------------------------------------------

WITH_OUT = (
    "gen.config:GenConfig",
    "gen.products.canonical:CanonicalOptions",
    "gen.export:ExportOptions",
    "gen.preview:PreviewOptions",
    "eval.__main__:EvalOptions",
    "eval.score:ScoreOptions",
    "eval.agreement:AgreementOptions",
    "eval.suites:SuitesOptions",
    "train.fit:TrainConfig",
    "train.experiment:ExperimentOptions",
    "train.axes:AxesOptions",
    "train.release:ReleaseOptions",
    "train.course:CourseOptions",
)


def _schema(name: str) -> type:
    module, cls = name.split(":")
    return getattr(importlib.import_module(module), cls)


def test_every_command_with_an_out_option_is_listed_here() -> None:
    declared = set()
    for package in ("gen", "eval", "train", "jobs", "bench"):
        for path in (ROOT / package).rglob("*.py"):
            for cls, body in re.findall(r"^class (\w+):\n((?:    .*\n|\n)*)", path.read_text(), re.M):
                if re.search(r"^    out: [^=\n]*=", body, re.M):  # an option (a field with a default)
                    declared.add(f"{'.'.join(path.relative_to(ROOT).with_suffix('').parts)}:{cls}")
    assert declared == set(WITH_OUT)


@pytest.mark.parametrize("name", WITH_OUT)
@pytest.mark.parametrize("empty", ["out=", "out=''", "out=' '"])
def test_an_empty_out_is_refused_by_every_command(name: str, empty: str) -> None:
    schema = _schema(name)
    required = [f"{f.name}=x" for f in dataclasses.fields(schema) if f.default is f.default_factory is dataclasses.MISSING]
    with pytest.raises(UserError, match=r"^out= is empty, which would mean the current folder"):
        compose_config(schema.__name__, schema, [*required, empty])
    compose_config(schema.__name__, schema, [*required, "out=somewhere"])  # a named one is taken


def test_an_empty_out_is_one_line_and_exit_2_before_any_work(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    ran: list[object] = []
    schema = _schema("eval.__main__:EvalOptions")
    assert main("python -m eval", schema, ran.append, ["policy=nothing", f"exam={tmp_path}", "out="]) == 2
    assert "out= is empty" in _one_line(capsys) and ran == []


# --- 5. the exam's hint, pasted into a shell ---------------------------------------------------------------


def test_the_take_hint_quotes_an_exam_path_with_spaces() -> None:
    from gen.products.exam import ExamSummary

    out = Path("/tmp/my exams/object exam")
    hint = str(ExamSummary(out, 3, 1.0, "ok")).splitlines()[-1]
    assert hint.startswith("take it with: python -m eval ")
    words = shlex.split(hint.removeprefix("take it with: "))
    assert words == ["python", "-m", "eval", "policy=<policy>", f"exam={out}"], words


# --- 6. the README's commands run from the venv ---------------------------------------------------------


def _command_lines(page: Path) -> list[str]:
    """The first line of each command in the page's shell blocks (not ```python ones), comments dropped."""
    lines, block, continued = [], None, False
    for line in page.read_text().splitlines():
        if line.startswith("```"):
            block = None if block is not None else line[3:].strip()
            continue
        if block not in ("", "sh", "bash", "shell"):
            continue
        if not continued and line.strip() and not line.lstrip().startswith("#"):
            lines.append(line.strip())
        continued = line.rstrip().endswith("\\")
    return lines


@pytest.mark.parametrize("page", ["README.md", "docs/TRAIN.md"])
def test_the_readmes_commands_of_tools_in_the_venv_are_spelled_venv_bin(page: str) -> None:
    tools = {p.name for p in Path(sys.prefix, "bin").iterdir()} | {"python", "python3", "pip", "lerobot-train", "ruff", "pytest"}
    bare = []
    for line in _command_lines(ROOT / page):
        words = [w for w in line.split() if not re.fullmatch(r"[A-Z_][A-Z0-9_]*=\S*", w)]  # VAR=x before the command
        if words and words[0] in tools:
            bare.append(line)
    assert bare == [], f"{page}: spell these .venv/bin/<tool> (a bare one is not on PATH): {bare}"
    assert any(line.startswith(".venv/bin/lerobot-train ") for line in _command_lines(ROOT / page))


# --- 7. RESULTS_FACES.md's commands against its tables ----------------------------------------------------


def _faces_commands() -> list[list[str]]:
    text = (ROOT / "docs" / "RESULTS_FACES.md").read_text()
    block = text.split("```\n", 2)[1]
    return [
        shlex.split(line, comments=True) for line in block.replace("\\\n", " ").splitlines() if shlex.split(line, comments=True)
    ]


def _faces_tables() -> dict[str, dict[str, str]]:
    """world -> the table's exam label and, per policy row of its switch table, the row."""
    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        from faces_results import BEGIN, END, WORLDS
    finally:
        sys.path.remove(str(ROOT / "scripts"))
    text = (ROOT / "docs" / "RESULTS_FACES.md").read_text()
    generated = text[text.index(BEGIN) : text.index(END)]
    by_label = {label: world for world, label in WORLDS.items()}
    tables: dict[str, dict[str, str]] = {}
    for label, exam, body in re.findall(r"^\*\*(.+?)\*\* \(`(.+?)`\)\n\n((?:\|.*\n)+)", generated, re.M):
        rows = {cells.split("|")[1].strip(): cells for cells in body.splitlines()[2:]}
        tables[by_label[label]] = {"exam": exam, **rows}
    return tables


def test_results_faces_commands_make_exactly_the_rows_of_its_tables() -> None:
    from eval.__main__ import EvalOptions
    from gen.config import GenConfig
    from gen.products.canonical import CanonicalOptions

    commands, tables = _faces_commands(), _faces_tables()
    exams: dict[str, tuple[str, object]] = {}  # out -> (world, options)
    taken: dict[tuple[str, str], EvalOptions] = {}
    for words in commands:
        module, args = (words[2], words[3:]) if words[:2] == ["python", "-m"] else (words[1], words[2:])
        if module == "gen":
            options = compose_config("GenConfig", GenConfig, args)
            exams[options.out] = ("native" if options.world in (None, "native") else options.world, options)
        elif module == "gen.canonical":
            options = compose_config("CanonicalOptions", CanonicalOptions, args)
            exams[options.out] = (options.world, options)
        elif module == "eval":
            options = compose_config("EvalOptions", EvalOptions, args)
            world, policy = Path(options.out).relative_to("runs/faces/reports").parts
            assert exams[options.exam][0] == world, f"{options.out} takes {options.exam}, an exam of another world"
            if options.policy.startswith("ckpt:"):
                checkpoint = Path(options.policy.removeprefix("ckpt:"))
                assert (ROOT / checkpoint).is_dir() and checkpoint.name.removesuffix("-lora").endswith(policy), options
            else:
                assert options.policy == policy, options
            taken[(world, policy)] = options
        else:
            assert words[:2] == ["python", "scripts/faces_results.py"], words
    rows = {(world, policy) for world, table in tables.items() for policy in table if policy != "exam"}
    assert set(taken) == rows, (
        f"commands make {sorted(set(taken) - rows)} the tables lack; tables have {sorted(rows - set(taken))}"
    )
    for world, table in tables.items():  # the exams the commands make are the ones the tables name
        _, options = next(exams[o.exam] for (w, _), o in taken.items() if w == world)
        if world == "native":
            assert f"seed{options.seed}/{options.n}trials" in table["exam"], (table["exam"], options)
            trials = options.n
        else:
            assert f"{options.states} per task, seed {options.seed}" in table["exam"], (table["exam"], options)
            trials = int(re.search(r"\((\d+) trials\)", table["exam"])[1])
        for policy, row in table.items():
            if policy != "exam":  # a switch row a trial at most (exam.json says why a trial has none)
                switched = int(re.search(r"/(\d+);", row.split("|")[3])[1])
                assert 0 < switched <= trials, (world, policy, row)


# --- 8. a missing path says it is missing -------------------------------------------------------------


def test_a_missing_exam_is_said_not_to_exist_and_a_folder_without_one_not_to_be_an_exam(tmp_path: Path) -> None:
    from core.exam import ExamError, read

    with pytest.raises(ExamError, match=rf"^exam={tmp_path / 'nowhere'} does not exist$"):
        read(tmp_path / "nowhere")
    with pytest.raises(ExamError, match=rf"^{tmp_path} is not an exam: no exam.json$"):
        read(tmp_path)
    (tmp_path / "a_file").write_text("x")
    with pytest.raises(ExamError, match="is a file, not an exam folder"):
        read(tmp_path / "a_file")


def test_eval_says_a_missing_exam_does_not_exist(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from eval.__main__ import EvalOptions, evaluate

    missing = tmp_path / "datasets" / "object-exam"
    assert main("python -m eval", EvalOptions, evaluate, ["policy=nothing", f"exam={missing}"]) == 2
    assert _one_line(capsys) == f"exam={missing} does not exist"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("command", "schema", "argv"),
    [
        ("gen.check", "gen.check:CheckOptions", ["{path}"]),
        ("gen.verify", "gen.verify:VerifyOptions", ["{path}"]),
        ("gen.push", "gen.push:PushOptions", ["root={path}", "repo_id=me/data"]),
    ],
)
def test_the_commands_that_read_a_folder_say_a_missing_one_does_not_exist(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str, schema: str, argv: list[str]
) -> None:
    module = importlib.import_module(command)
    missing = tmp_path / "nowhere"
    positional = None if command == "gen.push" else "dataset"
    args = [a.format(path=missing) for a in argv]
    assert main(f"python -m {command}", _schema(schema), module.run, args, positional=positional) == 2
    assert _one_line(capsys) == f"{missing} does not exist"
    (tmp_path / "a_file").write_text("x")
    args = [a.format(path=tmp_path / "a_file") for a in argv]
    assert main(f"python -m {command}", _schema(schema), module.run, args, positional=positional) == 2
    assert _one_line(capsys) == f"{tmp_path / 'a_file'} is not a folder"
