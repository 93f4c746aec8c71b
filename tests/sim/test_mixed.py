"""One dataset, many axes: `referent=[a,b,c]` writes one LeRobot dataset whose episodes take
turns among the types (n/k each), every type audited on its own, so that lerobot's own trainer,
which reads one dataset, fits one policy (and one LoRA) on every axis at once."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from lerobot.datasets.lerobot_dataset import LeRobotDataset  # lerobot's own loader, before any GL context
from PIL import Image

from core.profiles import ACTION_KEY, LIBERO, STATE_KEY
from core.spec import EpisodeSpec
from gen.config import GenConfig, parse
from gen.planning.plan import designs, plan_and_audit
from gen.products import scenes
from helpers import lerobot_train, make_dataset
from jobs.cli import main

ROOT = Path(__file__).resolve().parents[2]

# The reference study's seven types, each in the LIBERO scene that carries it: (as the list names
# it, the type its episodes record, their world, the type's name in the mix)
STUDY = (
    ("object@libero_object", "libero_object", "libero_object", "libero_object"),
    ("relation@libero_spatial", "libero_spatial", "libero_spatial", "libero_spatial"),
    ("goal@libero_goal", "libero_goal", "libero_goal", "libero_goal"),
    ("color@libero_spatial", "color", "libero_spatial", "color@libero_spatial"),
    ("category@libero_object", "category", "libero_object", "category@libero_object"),
    ("negation@libero_object", "negation", "libero_object", "negation@libero_object"),
    ("composition@libero_object", "composition", "libero_object", "composition@libero_object"),
)
ITEMS, TYPES, WORLDS, LABELS = (list(column) for column in zip(*STUDY))
MIXED = f"referent=[{','.join(ITEMS)}]"
ARGS = (MIXED, f"n={len(STUDY)}", "image_size=64", "seed=2", "workers=2")
FILES = (
    "data/chunk-000/file-000.parquet",
    "meta/scenes.parquet",
    "meta/episodes/chunk-000/file-000.parquet",
    "meta/tasks.parquet",
    "meta/stats.json",
    "meta/info.json",
    "meta/audit.json",
    "README.md",
    *(f"videos/{key}/chunk-000/file-000.mp4" for key in LIBERO.image_keys),
)


def _gen(*args: str, crash: str | None = None) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, **({"DECONFOUND_CRASH_AT": crash} if crash else {})}
    return subprocess.run([sys.executable, "-m", "gen", *ARGS, *args], capture_output=True, text=True, env=env)


@pytest.fixture(scope="module")
def mixed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("mixed") / "ds"
    done = _gen(f"out={out}")
    assert done.returncode == 0, done.stderr[-3000:]
    return out


def test_a_mix_is_one_lerobot_dataset_whose_episodes_take_turns(mixed: Path) -> None:
    ds = LeRobotDataset("local/mixed", root=mixed)
    assert ds.num_episodes == len(STUDY) and set(ds.meta.features) >= {*LIBERO.image_keys, STATE_KEY, ACTION_KEY}
    records = scenes.read(mixed)
    assert list(records["referent"]) == TYPES and list(records["world"]) == WORLDS
    assert [json.loads(scene)["world"] for scene in records["scene"]] == WORLDS
    for ep in range(len(STUDY)):
        item = ds[ds.meta.episodes[ep]["dataset_from_index"]]
        assert item["task"] == records["instruction"][ep]
        assert tuple(item["observation.images.image"].shape) == (3, 64, 64)
    generation = json.loads((mixed / "meta/generation.json").read_text())
    assert generation["config"]["referent"] == ITEMS and sorted(generation["referent_spec"]) == sorted(LABELS)
    check = subprocess.run([sys.executable, "-m", "gen.check", str(mixed)], capture_output=True, text=True)
    assert check.returncode == 0, check.stderr
    doctor = Path(sys.executable).with_name("lerobot-doctor")
    report = json.loads(subprocess.run([str(doctor), "check", str(mixed), "--json"], capture_output=True, text=True).stdout)
    assert not [m for c in report["checks"] for m in c["messages"] if m["severity"] == "FAIL"]
    assert report["overall_severity"] in ("PASS", "WARN")


def test_every_type_has_its_own_audit_and_card_section(mixed: Path) -> None:
    audits = json.loads((mixed / "meta/audit.json").read_text())["referents"]
    assert list(audits) == LABELS
    for (_, name, world, label), record in zip(STUDY, audits.values()):
        assert record["agree"] and record["written"]["referent"] == name and not record["written"]["leaks"]
        assert record["written"]["episodes"] == 1
    card = (mixed / "README.md").read_text()
    for _, name, world, label in STUDY:
        assert f"## `{label}` (world {world})" in card and f"- referent-{name}" in card
        where = "" if label == name else f" world={world}"
        assert f"python -m gen referent={name}{where} image_size=64 fps=20 profile=libero n=200 seed=3 split=exam" in card
    assert f"python -m gen '{MIXED}' n={len(STUDY)} seed=2 image_size=64" in card


def test_verify_regenerates_each_type_from_its_spec(mixed: Path) -> None:
    every = len(STUDY)
    done = subprocess.run([sys.executable, "-m", "gen.verify", str(mixed), f"episodes={every}"], capture_output=True, text=True)
    assert done.returncode == 0 and f"episodes {list(range(every))} regenerate identically" in done.stdout, done.stderr[-2000:]


def test_lerobot_train_fits_act_and_a_lora_of_it_on_a_mix(mixed: Path, tmp_path: Path) -> None:
    act = lerobot_train(
        tmp_path / "act",
        mixed,
        type="act",
        pretrained_backbone_weights="null",  # ImageNet weights would be downloaded
        dim_model=64,
        dim_feedforward=128,
        chunk_size=10,
        n_action_steps=10,
    )
    assert (act / "model.safetensors").is_file()
    lora = lerobot_train(tmp_path / "lora", mixed, path=act)
    assert (lora / "adapter_config.json").is_file() and json.loads((lora / "config.json").read_text())["use_peft"]


def test_batches_draw_each_type_of_a_mix_equally(mixed: Path) -> None:
    """Training reads a mix's frames memory-mapped, knows each episode's type, and (balance=true)
    draws every type equally often though their episodes differ in length."""
    from train import data

    frames = data.load(str(mixed))
    assert all(isinstance(images, np.memmap) for images in frames.images.values())
    assert frames.referent is not None and len(set(frames.referent)) == 7
    drawn = frames.referent[frames.episode[data.sample(frames, np.random.default_rng(0), 7000, balance=True)]]
    shares = [np.mean(drawn == r) for r in set(frames.referent)]
    assert max(abs(s - 1 / 7) for s in shares) < 0.03, shares
    uniform = frames.referent[frames.episode[data.sample(frames, np.random.default_rng(0), 7000, balance=False)]]
    lengths = frames.ends - frames.starts
    longest = frames.referent[int(np.argmax(lengths))]
    assert np.mean(uniform == longest) > np.mean(drawn == longest)  # without balance, a longer type weighs more
    group = data.groups(frames)
    chances = data.favoured(frames, group, ["libero_goal", "color"], 0.5)  # a fix for lagging types
    favoured = frames.referent[frames.episode[data.sample(frames, np.random.default_rng(0), 7000, True, group, chances)]]
    assert abs(np.mean(favoured == "libero_goal") - 0.25) < 0.03 and abs(np.mean(favoured == "negation") - 0.1) < 0.03
    with pytest.raises(data.DatasetError, match="some, not all, of the referent types"):
        data.favoured(frames, group, ["goal"], 0.5)  # the type LIBERO-Goal's episodes record is libero_goal


def test_a_picture_of_each_types_first_frame(mixed: Path) -> None:
    """scripts/first_frames.py: one tile per type, each under its instruction, written beside the
    dataset (in it, `gen ... overwrite=true` would refuse it as the user's and gen.push would upload it)."""
    inside = sorted(p.relative_to(mixed) for p in mixed.rglob("*"))
    script = ROOT / "scripts" / "first_frames.py"
    done = subprocess.run([sys.executable, str(script), str(mixed)], capture_output=True, text=True)
    assert done.returncode == 0 and f"({len(STUDY)} types" in done.stdout, done.stderr[-2000:]
    out = mixed.parent / f"{mixed.name}-first_frames.png"
    assert Image.open(out).width == len(STUDY) * 192
    assert sorted(p.relative_to(mixed) for p in mixed.rglob("*")) == inside
    out.unlink()


def test_a_killed_mix_resumes_to_the_same_bytes(mixed: Path, tmp_path: Path) -> None:
    """SIGKILL mid-run (two workers: they die with it, or their open pipes would hold this test
    forever), then resume=true: the same bytes as the uninterrupted run."""
    out = tmp_path / "ds"
    assert _gen(f"out={out}", crash="episode:1").returncode == -9
    assert not out.exists()
    resumed = _gen(f"out={out}", "resume=true")
    assert resumed.returncode == 0, resumed.stderr[-2000:]
    for rel in FILES:
        assert (out / rel).read_bytes() == (mixed / rel).read_bytes(), rel


def test_a_mix_of_native_types(tmp_path: Path) -> None:
    out = make_dataset(tmp_path / "native", "referent=[object,color]", "n=2", "image_size=32", "seed=1", "workers=1")
    records = scenes.read(out)
    assert list(records["referent"]) == ["object", "color"] and list(records["world"]) == ["native", "native"]
    assert LeRobotDataset("local/native", root=out).num_episodes == 2
    assert list(json.loads((out / "meta/audit.json").read_text())["referents"]) == ["object", "color"]


def test_a_mixed_plan_holds_each_types_own_plan_in_turns(tmp_path: Path) -> None:
    """Each type's episodes have the roles its own plan of n/k draws with the same seed in a stream
    of its own, every type taking its turn, and each type's audit (20 episodes each) finds no leak."""
    mixed = plan_and_audit(parse(["referent=[object,color,category]", "n=60", f"out={tmp_path / 'mix'}"]))
    assert [spec.referent for spec in mixed.specs[:6]] == ["object", "color", "category"] * 2
    for place, share in enumerate(mixed.shares):
        assert mixed.designs[place::3] == designs(share.referent, 20, 0, stream=share.referent.label)
        assert share.audit["verdict"] == "no leak"


def test_a_mix_confounds_each_type_its_own_way(tmp_path: Path) -> None:
    """`confound=[...]` gives each type of a mix its own confound (the release's confounded arm):
    LIBERO-Spatial's and LIBERO-Goal's tasks laid out as LIBERO lays them out, another type's
    target in its canonical slot, a type left deconfounded; each audited as such."""
    mixed = plan_and_audit(
        parse(["referent=[relation@libero_spatial,goal@libero_goal,color@libero_spatial]", "n=150",
               "confound=[layout,layout,null]", f"out={tmp_path / 'mix'}"])
    )  # fmt: skip
    relation, goal, color = mixed.shares
    assert (relation.referent.config.confound, goal.referent.config.confound, color.referent.config.confound) == (
        "layout", "layout", None,
    )  # fmt: skip
    assert relation.audit["leaks"] and color.audit["verdict"] == "no leak"  # the layout says which bowl
    bowls = {tuple(sorted(o.slot for o in s.objects if o.kind == "akita_black_bowl")) for s in mixed.specs[0::3]}
    assert len(bowls) <= 8  # LIBERO-Spatial's own pairs of places, not every pair
    assert len({tuple((o.kind, o.slot) for o in s.objects) for s in mixed.specs[1::3]}) == 1  # LIBERO-Goal's one layout


def test_types_of_alike_scenes_never_share_their_scenes_in_a_mix(tmp_path: Path) -> None:
    """Negation and composition lay out the same four groceries the same way: drawn from one stream
    they gave one seed's episodes identical scenes and the same target; each draws from its own."""
    both = "referent=[negation@libero_object,composition@libero_object]"
    mixed = plan_and_audit(parse([both, "n=40", f"out={tmp_path / 'm'}"]))

    def scene(spec: EpisodeSpec) -> tuple:
        return (tuple(sorted((o.kind, o.slot) for o in spec.objects)), spec.object(spec.target).kind)

    pairs = list(zip(mixed.specs[0::2], mixed.specs[1::2]))
    same = sum(scene(a) == scene(b) for a, b in pairs)
    assert same < len(pairs) / 4, f"{same} of {len(pairs)} episode pairs share their scene and target"


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["referent=[object,unicorn]", "n=2"], "unknown referent 'unicorn'"),
        (["referent=[object,color,object]", "n=3"], "referent=[object,color,object] names object 2 times: name each type once"),
        ([MIXED, "n=8"], f"n=8 cannot be shared equally by the 7 types of {MIXED}: give n=7"),
        (["referent=[color@libero_spatial,verb@libero_object]", "n=2"], "verb@libero_object: referent verb has no design"),
        (["referent=[color@libero_spatial,color@libero_spatial]", "n=2"], "names color@libero_spatial 2 times"),
        (["referent=[object,color]", "n=3"], "give n=2 or n=4"),
        (["referent=[object,libero_object]", "n=2"], "object records profile native"),
        (["referent=[]"], "referent=[] names no referent type"),
        ([MIXED, "n=7", "split=exam"], "split=exam makes one exam per referent type"),
        ([MIXED, "n=7", "confound=[layout,position]"], "names 2 confounds for the 7 types"),
        (["referent=object", "n=2", "confound=[position]"], "is one per type of a referent list; object is one type"),
        (
            ["referent=[object@libero_object,color@libero_spatial]", "n=2", "confound=[layout,layout]"],
            "'layout' is not defined for referent type 'color'",
        ),
    ],
)
def test_bad_lists_are_refused_in_one_line(
    argv: list[str], needle: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from gen.__main__ import generate

    out = tmp_path / "out"
    assert main("python -m gen", GenConfig, generate, [*argv, f"out={out}"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0], lines
    assert not out.exists()
