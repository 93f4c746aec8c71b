"""The train stage wired end to end on a tiny dataset: a few steps with the real MiniLM text
tower and LoRA, a resumable checkpoint, an exam trial taken with it, and clear errors for
datasets it cannot learn from (the experiment, not CI, proves the effect)."""

from __future__ import annotations

import dataclasses
import json
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import torch

from core.exam import read
from core.profiles import NATIVE
from eval.policies import FeatureMismatch
from eval.policies.registry import make
from eval.scoring.battery import take
from gen.config import parse
from gen.lerobot.stats import image_histogram
from gen.lerobot.video import encode_episode
from gen.lerobot.writer import Episode, LeRobotWriter, Recording
from helpers import ONE_TRIAL_64, Shared, make_dataset
from jobs.cli import UserError, main
from train.fit import STABLE, TrainConfig, _shift, fit, kept_steps, point_loss, schedule, snapshot_file
from train.stages import TIMINGS, Ledger, made


@pytest.fixture(scope="module")
def checkpoint(object_dataset: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("ckpt")
    cfg = TrainConfig(dataset=str(object_dataset), out=str(out), steps=3, batch_size=4, save_every=2, log_every=1, keep_every=2)
    fit(cfg, progress=False)
    return out


def test_training_writes_a_checkpoint_and_resumes(checkpoint: Path, object_dataset: Path, tmp_path: Path) -> None:
    log = json.loads((checkpoint / "train.json").read_text())
    assert log["steps"] == 3 and np.isfinite(log["final_loss"]) and log["tasks"] == 4
    assert (checkpoint / "model.pt").is_file() and (checkpoint / "last.pt").is_file()
    assert make(f"ckpt:{checkpoint / snapshot_file(2)}").model.config == make(f"ckpt:{checkpoint}").model.config  # kept at step 2
    assert not (checkpoint / snapshot_file(3)).exists()  # the last step is model.pt itself
    lora_only = log["trainable_parameters"]
    assert 0 < lora_only < 5_000_000  # the text tower's 22.7M pretrained weights stay frozen under LoRA
    resumed = fit(TrainConfig(dataset=str(object_dataset), out=str(checkpoint), steps=5, batch_size=4, resume=True, log_every=1))
    assert [h["step"] for h in resumed["history"]] == [1, 2, 3, 4, 5]
    assert kept_steps(checkpoint, 5) == [2]  # the extended run keeps its shorter start's snapshot
    # Extending a finished run is training longer (what `python -m train.experiment steps=` relies on).
    straight = tmp_path / "straight"
    fit(TrainConfig(dataset=str(object_dataset), out=str(straight), steps=5, batch_size=4, log_every=1), progress=False)
    extended, direct = (torch.load(d / "model.pt", weights_only=False)["weights"] for d in (checkpoint, straight))
    assert extended.keys() == direct.keys() and all(torch.equal(extended[k], direct[k]) for k in direct)


def test_a_cooled_run_extends_from_where_its_cool_down_began(object_dataset: Path, tmp_path: Path) -> None:
    def train(out: Path, steps: int, **schedule: float) -> dict:
        cfg = TrainConfig(dataset=str(object_dataset), out=str(out), steps=steps, batch_size=4, log_every=1, resume=True)
        return fit(dataclasses.replace(cfg, **schedule), progress=False)

    run = tmp_path / "run"
    train(run, 3)  # a constant learning rate, then two cool-downs of 2 steps
    train(run, 5, decay=2, lr_floor=0.1)
    cooled = train(run, 7, decay=2, lr_floor=0.1)  # last.pt (step 5) cooled too early: stable.pt (step 3) is taken
    rates = [round(h["lr"] / cooled["config"]["lr"], 3) for h in cooled["history"]]
    assert rates == [1.0] * 6 + [0.55]
    straight = train(tmp_path / "straight", 7, decay=2, lr_floor=0.1)
    assert straight["history"] == cooled["history"]
    extended, direct = (torch.load(d / "model.pt", weights_only=False)["weights"] for d in (run, tmp_path / "straight"))
    assert all(torch.equal(extended[k], direct[k]) for k in direct)
    with pytest.raises(ValueError, match="another learning-rate schedule"):
        train(run, 9, lr_floor=0.5)  # a cosine over every step: no saved state had its learning rates
    branched = train(tmp_path / "branch", 7, decay=2, lr_floor=0.1, branch=str(run / STABLE))  # its step 5
    assert branched["history"] == straight["history"]  # the same cool-down redone in another folder
    again = torch.load(tmp_path / "branch" / "model.pt", weights_only=False)["weights"]
    assert all(torch.equal(again[k], direct[k]) for k in direct) and (run / "model.pt").is_file()
    with pytest.raises(ValueError, match="branch=.* another learning-rate schedule"):
        train(tmp_path / "other", 9, lr_floor=0.5, branch=str(run / STABLE))


def test_the_learning_rate_warms_up_then_follows_a_cosine_to_its_floor() -> None:
    cfg = TrainConfig(steps=1000, warmup=100, lr_floor=0.05)
    rates = [schedule(cfg, step) for step in range(cfg.steps)]
    assert rates[0] == pytest.approx(0.01) and rates[99] == pytest.approx(1.0)  # linear warm-up
    assert all(a >= b for a, b in zip(rates[100:], rates[101:]))  # then never rises
    assert rates[550] == pytest.approx(0.05 + 0.95 * 0.5)  # half-way down the cosine
    assert schedule(cfg, cfg.steps) == pytest.approx(0.05)
    cool = TrainConfig(steps=1000, decay=200, lr_floor=0.0)  # constant, then a cool-down
    assert [schedule(cool, step) for step in (0, 800, 900)] == pytest.approx([1.0, 1.0, 0.5])


def test_a_checkpoint_takes_an_exam(checkpoint: Path, shared: Shared, tmp_path: Path) -> None:
    exam = read(shared.dataset("exam", *ONE_TRIAL_64))
    report, _ = take(exam, exam.trials.head(2), make(f"ckpt:{checkpoint}"), tmp_path / "report")
    assert not report["errors"], report["errors"]
    assert report["faces"]["task"]["n"] == 1
    policy, features = make(f"ckpt:{checkpoint}"), exam.features
    for key, other in (("observation.images.agentview", (32, 32, 3)), ("observation.state", (8,)), ("action", (7,))):
        with pytest.raises(FeatureMismatch, match=f"expects '{key}' of shape {re.escape(str(features[key]))}"):
            policy.check({**features, key: other})
    smaller = dataclasses.replace(exam, meta={**exam.meta, "observation": {**exam.meta["observation"], "image_size": 32}})
    with pytest.raises(FeatureMismatch, match="of shape \\(64, 64, 3\\), this exam's is \\(32, 32, 3\\)"):
        take(smaller, smaller.trials, policy, tmp_path / "refused")
    assert not (tmp_path / "refused").exists()  # refused before any rollout


def _synthetic(root: Path, tasks: list[str], cameras: tuple[str, ...] = ("agentview", "wrist"), size: int = 32) -> Path:
    writer = LeRobotWriter(root, Recording(20, size, cameras, NATIVE.state_names, NATIVE.action_names))
    for task in tasks:
        frames = np.random.default_rng(0).integers(0, 255, (5, size, size, 3), dtype=np.uint8)
        writer.add(
            Episode(
                task,
                np.zeros((5, 16), np.float32),
                np.zeros((5, 8), np.float32),
                {c: encode_episode(frames, 20) for c in cameras},
                {c: image_histogram(frames) for c in cameras},
            )
        )
    writer.finalize()
    return root


def _train(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "train", *args, "steps=1"], capture_output=True, text=True)


def _refusal(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, list[str]]:
    """`python -m train *args steps=1` run as its entry point runs it (jobs.cli.main), in this process
    (a refusal comes before any training, and a process of its own costs seconds of imports): its
    exit code and the lines it wrote to stderr."""
    from train.__main__ import train

    capsys.readouterr()
    code = main("python -m train", TrainConfig, train, [*args, "steps=1"])
    return code, capsys.readouterr().err.strip().splitlines()


def test_datasets_it_cannot_learn_from_are_refused(
    tmp_path: Path, object_dataset: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    same = _synthetic(tmp_path / "same", ["pick up the lemon"] * 3)
    result = _train(f"dataset={same}", f"out={tmp_path / 'ckpt'}")  # once as its own process: one line, as a user sees it
    assert result.returncode == 2 and len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert "no instruction diversity" in result.stderr, result.stderr
    cases = [
        (_synthetic(tmp_path / "onecam", ["a", "b"], cameras=("agentview",)), "native misses 'observation.images.wrist'"),
        (tmp_path / "nothing", "is not a LeRobot dataset"),
    ]
    for dataset, needle in cases:
        code, lines = _refusal(capsys, f"dataset={dataset}", f"out={tmp_path / 'ckpt'}")
        assert code == 2 and len(lines) == 1 and needle in lines[0], lines
    code, lines = _refusal(capsys, f"dataset={object_dataset}", "image_size=96", f"out={tmp_path / 'ckpt'}")
    assert code == 2 and "frames are 64 px but image_size=96" in "\n".join(lines)
    assert "regenerate the dataset with image_size=96" in "\n".join(lines)
    code, lines = _refusal(capsys, f"dataset={object_dataset}", "image_size=7", f"out={tmp_path / 'ckpt'}")
    assert code == 2 and len(lines) == 1 and "train with image_size=64" in lines[0]
    assert "image_size=7" in lines[0] and "regenerate" not in lines[0] and "not a size python -m gen makes" in lines[0]
    for weight in ("point_weight", "aux_weight"):  # a negative loss weight would train away from the target
        code, lines = _refusal(capsys, f"dataset={object_dataset}", f"{weight}=-1", f"out={tmp_path / 'ckpt'}")
        assert code == 2 and len(lines) == 1 and f"{weight} must be at least 0, got -1.0" in lines[0]
    for picked in ("switched_first=10", "switched_before=10", "switched_stay=true"):
        code, lines = _refusal(capsys, f"dataset={object_dataset}", picked, f"out={tmp_path / 'ckpt'}")
        assert code == 2 and len(lines) == 1 and "set switched_share too" in lines[0], lines  # recorded, never applied
    both = ("switched_share=0.5", "switched_before=10", "switched_stay=true")
    code, lines = _refusal(capsys, f"dataset={object_dataset}", *both, f"out={tmp_path / 'ckpt'}")
    assert code == 2 and len(lines) == 1 and "set one" in lines[0], lines
    assert not (tmp_path / "ckpt").exists()


def test_the_pointer_is_taught_where_the_target_is_until_the_grasp(object_dataset: Path) -> None:
    """point_weight: the loss is least where the map peaks on the target's pixel, follows the
    image shift, and counts only the frames before the gripper first closes."""
    from train import data

    frames = data.load(str(object_dataset))
    reaching = data.until_grasp(frames)
    for start, end in zip(frames.starts, frames.ends):
        first = start + int(np.argmin(reaching[start:end]))
        assert reaching[start] and not reaching[end - 1] and frames.action[first, -1] > 0
        assert (frames.action[start:first, -1] <= 0).all()
    images = np.zeros((8, 64, 64, 3), np.uint8)
    images[:, 20, 40] = 255  # row 20, column 40
    moved, offsets = _shift(images, 4, np.random.default_rng(1))
    assert offsets.any(axis=1).sum() >= 4
    for image, (dx, dy) in zip(moved, offsets):
        assert [tuple(p) for p in np.argwhere(image[:, :, 0])] == [(20 + dy, 40 + dx)]
    logits = torch.full((2, 16, 16), -5.0)
    logits[0, 5, 10] = logits[1, 10, 5] = 5.0  # a 64 px image's row 20, column 40 is cell (5, 10)
    losses = point_loss(logits, torch.tensor([[40.0, 20.0]] * 2), 64)
    assert losses[0] < losses[1]


def test_one_policy_trains_on_several_datasets(object_dataset: Path, tmp_path: Path) -> None:
    """`dataset=[a,b]`: the union's frames, episodes and instructions, statistics over all frames,
    batches drawn from each dataset equally; datasets that disagree are refused in one line."""
    from train import data

    color = make_dataset(tmp_path / "color", "referent=color", "n=2", "image_size=64", "seed=3")
    one, other = data.load(str(object_dataset)), data.load(str(color))
    union = data.load([str(object_dataset), str(color)])
    assert len(union) == len(one) + len(other) and union.sources == [str(object_dataset), str(color)]
    assert len(union.starts) == len(one.starts) + len(other.starts) and union.ends[-1] == len(union)
    assert set(union.tasks) == set(one.tasks) | set(other.tasks)
    assert [union.tasks[t] for t in union.task[len(one) :]] == [other.tasks[t] for t in other.task]
    for camera, images in union.images.items():  # each set's frames still memory-mapped, none copied
        assert all(isinstance(part, np.memmap) for part in images.parts) and images.shape[0] == len(union)
        picked = np.array([len(one) + 1, 0, len(union) - 1, 1])
        seen = np.stack([other.images[camera][1], one.images[camera][0], other.images[camera][-1], one.images[camera][1]])
        assert np.array_equal(images[picked], seen) and np.array_equal(images[len(one)], other.images[camera][0])
    both = np.concatenate([one.state, other.state])
    np.testing.assert_allclose(union.stats["observation.state"]["mean"], both.mean(0), rtol=1e-6)
    np.testing.assert_allclose(union.stats["observation.state"]["std"], both.std(0), rtol=1e-5, atol=1e-7)
    drawn = union.source[data.sample(union, np.random.default_rng(0), 4000, balance=True)]
    assert abs(np.mean(drawn == 1) - 0.5) < 0.05  # equal shares although the datasets differ in size
    both = [str(object_dataset), str(color)]
    pointed = TrainConfig(dataset=both, out=str(tmp_path / "ckpt"), steps=2, batch_size=4, point_weight=1.0)
    fit(pointed, progress=False)
    assert (tmp_path / "ckpt" / "model.pt").is_file()
    small = make_dataset(tmp_path / "small", "referent=color", "n=2", "image_size=32", "seed=3")
    refused = _train(f"dataset=[{object_dataset},{small}]", f"out={tmp_path / 'no'}")
    lines = refused.stderr.strip().splitlines()
    assert refused.returncode == 2 and len(lines) == 1 and "frame size [32, 32, 3]" in lines[0], refused.stderr
    twice = _train(f"dataset=[{object_dataset},{object_dataset}]", f"out={tmp_path / 'no'}")
    assert twice.returncode == 2 and "lists a folder twice" in twice.stderr and not (tmp_path / "no").exists()


def test_a_checkpoint_served_over_openpi_takes_an_exam(checkpoint: Path, shared: Shared, tmp_path: Path) -> None:
    server = subprocess.Popen(
        [sys.executable, "-m", "eval.serve", f"policy=ckpt:{checkpoint}", "port=0"], stdout=subprocess.PIPE, text=True
    )
    try:
        line = server.stdout.readline()
        assert line.startswith("serving"), line
        address = line.strip().rsplit("ws://", 1)[1]
        exam = read(shared.dataset("exam", *ONE_TRIAL_64))
        report, _ = take(exam, exam.trials.head(1), make(f"remote:{address}"), tmp_path / "report")
        assert not report["errors"], report["errors"]
    finally:
        server.kill()


def test_two_experiment_processes_add_to_one_ledger(tmp_path: Path) -> None:
    """The arms of an experiment trained side by side keep both their times in timings.json, and a
    stage stopped by Ctrl-C keeps the time it worked."""
    first, second = Ledger(tmp_path), Ledger(tmp_path)
    first.add("train a", 1.0)
    second.add("train b", 1.0)
    first.add("train a", 1.0)
    with pytest.raises(KeyboardInterrupt), second.timing("generate c"):  # stopped part way: its work so far counts
        time.sleep(0.2)
        raise KeyboardInterrupt
    spent = json.loads((tmp_path / TIMINGS).read_text())
    assert set(spent) == {"train a", "train b", "generate c"} and spent["train a"] >= 2.0 > spent["train b"] >= 1.0
    assert spent["generate c"] >= 0.2


def test_a_killed_stage_keeps_the_time_it_worked(tmp_path: Path) -> None:
    """A stage's process killed outright (a sitting's end: no `finally` runs) loses at most the last
    `FLUSH_S` of its time: the ledger adds a running stage's time as it goes."""
    code = (
        "import sys, time; from pathlib import Path; from train import stages; stages.FLUSH_S = 0.1\n"
        "with stages.Ledger(Path(sys.argv[1])).timing('take a'):\n    print('began', flush=True); time.sleep(60)"
    )
    worker = subprocess.Popen([sys.executable, "-c", code, str(tmp_path)], stdout=subprocess.PIPE, text=True)
    assert worker.stdout is not None and worker.stdout.readline().strip() == "began"
    time.sleep(1.5)
    worker.kill()
    worker.wait()
    assert json.loads((tmp_path / TIMINGS).read_text())["take a"] >= 1.0


def test_an_experiment_reuses_a_product_only_if_its_options_made_it(object_dataset: Path, shared: Shared) -> None:
    """A dataset or exam already in a stage's folder is reused only when made with the stage's
    options (not merely because something finished is there); another is refused, naming it."""
    exam = shared.dataset("exam", *ONE_TRIAL_64)
    dataset_options = ("referent=object", "n=4", "image_size=64", "overwrite=true", "resume=true")
    assert made(parse([f"out={object_dataset}", *dataset_options, "seed=7"]), object_dataset)
    assert made(parse([f"out={exam}", *ONE_TRIAL_64, "overwrite=true", "resume=true"]), exam)
    nothing = object_dataset.parent / "nothing"
    assert not made(parse([f"out={nothing}", *dataset_options]), nothing)
    with pytest.raises(UserError, match="another seed"):
        made(parse([f"out={object_dataset}", *dataset_options, "seed=8"]), object_dataset)
    with pytest.raises(UserError, match="holds the exam .*seed=0.*, not .*seed=2"):
        made(parse([f"out={exam}", *ONE_TRIAL_64, "seed=2", "overwrite=true", "resume=true"]), exam)
