"""A lab's LeRobot checkpoint takes the exam: lerobot's own `lerobot-train` fits ACT on a tiny
generated dataset (CPU, a handful of steps, no pretrained backbone: nothing downloads), and the
checkpoint it saves takes an exam trial through `policy=lerobot:`, and so does the LoRA adapter
`lerobot-train --peft...` fits on top of it; checkpoints whose features do not match the exam's are
refused before any rollout, with one line."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from peft import PeftModel

from core.exam import read
from core.profiles import ACTION_KEY, IMAGE_PREFIX, TASK_KEY
from eval.policies import FeatureMismatch, PolicyError
from eval.policies.registry import make
from helpers import ONE_TRIAL_64, Shared, lerobot_train

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def act_checkpoint(object_dataset: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    tiny = {"dim_model": 64, "dim_feedforward": 128, "chunk_size": 10, "n_action_steps": 10}
    # pretrained_backbone_weights=null: ImageNet weights would be downloaded
    return lerobot_train(
        tmp_path_factory.mktemp("act") / "run", object_dataset, type="act", pretrained_backbone_weights="null", **tiny
    )


@pytest.fixture(scope="module")
def lora_checkpoint(act_checkpoint: Path, object_dataset: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """lerobot's own LoRA fine-tune of the ACT checkpoint, as a lab makes one: its folder holds only the adapter.
    Its learning rate of 0.01 moves the adapter far enough in two steps to change the actions."""
    return lerobot_train(tmp_path_factory.mktemp("lora") / "run", object_dataset, path=act_checkpoint, optimizer_lr=0.01)


@pytest.fixture(scope="module")
def exam_64(shared: Shared) -> Path:
    return shared.dataset("exam", *ONE_TRIAL_64)


def _eval(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "eval", *args], capture_output=True, text=True, cwd=ROOT)


def test_a_lerobot_train_checkpoint_takes_an_exam_trial(act_checkpoint: Path, exam_64: Path, tmp_path: Path) -> None:
    done = _eval(f"policy=lerobot:{act_checkpoint}", f"exam={exam_64}", "rows=1", f"out={tmp_path / 'report'}")
    assert done.returncode == 0, done.stderr[-2000:]
    report = json.loads((tmp_path / "report" / "report.json").read_text())
    assert not report["errors"], report["errors"]
    assert report["faces"]["task"]["n"] == 1


def test_a_checkpoint_with_other_cameras_is_refused_before_any_rollout(
    act_checkpoint: Path, exam_64: Path, tmp_path: Path
) -> None:
    other = tmp_path / "renamed"
    shutil.copytree(act_checkpoint, other)
    config = other / "config.json"
    config.write_text(config.read_text().replace("observation.images.wrist", "observation.images.front"))
    done = _eval(f"policy=lerobot:{other}", f"exam={exam_64}", f"out={tmp_path / 'report'}")
    assert done.returncode == 2
    assert done.stderr.strip().splitlines()[-1] == (
        f"error: checkpoint {other} expects 'observation.images.front', which this exam does not have "
        "(it has observation.images.agentview, observation.images.wrist, observation.state, action)"
    )
    assert not (tmp_path / "report").exists()


@pytest.mark.parametrize(
    ("key", "other"), [("observation.state", (8,)), ("action", (7,)), ("observation.images.wrist", (32, 32, 3))]
)
def test_a_checkpoint_with_another_state_action_or_frame_size_is_refused(
    act_checkpoint: Path, exam_64: Path, key: str, other: tuple[int, ...]
) -> None:
    policy = make(f"lerobot:{act_checkpoint}")
    features = read(exam_64).features
    policy.check(features)  # the exam it was trained for fits
    with pytest.raises(FeatureMismatch) as refused:
        policy.check({**features, key: other})
    assert str(refused.value) == f"checkpoint {act_checkpoint} expects '{key}' of shape {features[key]}, this exam's is {other}"


def test_a_lerobot_lora_checkpoint_takes_an_exam_trial(lora_checkpoint: Path, exam_64: Path, tmp_path: Path) -> None:
    assert (lora_checkpoint / "adapter_config.json").is_file()
    assert not (lora_checkpoint / "model.safetensors").exists()
    assert json.loads((lora_checkpoint / "config.json").read_text())["use_peft"]
    done = _eval(f"policy=lerobot:{lora_checkpoint}", f"exam={exam_64}", "rows=1", f"out={tmp_path / 'report'}")
    assert done.returncode == 0, done.stderr[-2000:]
    report = json.loads((tmp_path / "report" / "report.json").read_text())
    assert not report["errors"], report["errors"]
    assert report["faces"]["task"]["n"] == 1


def test_a_lora_checkpoint_acts_as_its_base_with_the_adapter_applied(
    act_checkpoint: Path, lora_checkpoint: Path, exam_64: Path
) -> None:
    features = read(exam_64).features
    rng = np.random.default_rng(0)
    observation: dict = {TASK_KEY: "pick up the cube"}
    for key, shape in features.items():
        if key.startswith(IMAGE_PREFIX):
            observation[key] = rng.integers(0, 256, shape, dtype=np.uint8)
        elif key != ACTION_KEY:
            observation[key] = rng.standard_normal(shape).astype(np.float32)
    base, lora = make(f"lerobot:{act_checkpoint}"), make(f"lerobot:{lora_checkpoint}")
    assert isinstance(lora.policy, PeftModel)
    lora.check(features)
    assert not np.allclose(base.act(observation), lora.act(observation))


def test_a_lora_checkpoint_whose_base_is_gone_is_refused_saying_where_it_looked(lora_checkpoint: Path, tmp_path: Path) -> None:
    moved = tmp_path / "lora"
    shutil.copytree(lora_checkpoint, moved)
    adapter = moved / "adapter_config.json"
    gone = tmp_path / "gone" / "pretrained_model"
    adapter.write_text(json.dumps(json.loads(adapter.read_text()) | {"base_model_name_or_path": str(gone)}))
    with pytest.raises(PolicyError) as refused:
        make(f"lerobot:{moved}")
    assert str(refused.value) == (
        f"{moved}: cannot load the base policy its adapter_config.json names ({gone}): no folder {gone}"
    )
