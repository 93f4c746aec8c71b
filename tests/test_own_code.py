"""An exam taken the way another lab takes it: its own loop over the documented gymnasium env and
exam format, no import of our policies or oracle, logs scored offline — and nothing the policy
side receives holds the answer."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pandas as pd

from helpers import make_dataset

ANSWER = {"target", "program", "face", "variant", "spec", "alternatives", "original_target", "counterfactuals"}


def reach_the_named_object(instruction: str, scene: dict, geometry: dict, state: np.ndarray) -> np.ndarray:
    """A scripted libero-profile policy: bring the hand 3 cm above the grasp point (exam.json's
    geometry: top centre minus grasp depth) of whatever object the instruction names, with
    end-effector deltas and the gripper open; hold still when it names nothing."""
    named = [o for o in scene["objects"] if o["name"] in instruction]
    if not named:
        return np.array([0, 0, 0, 0, 0, 0, -1], np.float32)
    obj = max(named, key=lambda o: len(o["name"]))
    shape = geometry[obj["kind"]]
    grasp = np.asarray(obj["pos"]) + [0.0, 0.0, shape["size"][2] - shape["bottom"] - shape["grasp_depth"]]
    goal = grasp + [0.0, 0.0, 0.03]
    delta = np.clip(3.0 * (goal - state[:3]) / 0.05, -1.0, 1.0)
    return np.array([*delta, 0, 0, 0, -1], np.float32)


def test_a_lab_policy_on_the_documented_env_takes_the_exam(tmp_path: Path) -> None:
    root = make_dataset(tmp_path / "exam", "n=10", "split=exam", "seed=4", "profile=libero", "image_size=32")
    trials = pd.read_parquet(root / "trials.parquet")  # the policy's side of the exam
    geometry = json.loads((root / "exam.json").read_text())["geometry"]
    assert not ANSWER & set(trials.columns)
    logs = []
    for row in trials.itertuples():
        scene = json.loads(row.scene)
        assert scene["target"] == "" and scene["counterfactuals"] == [] and scene["instruction"] == ""
        env = gym.make("deconfound_exam:deconfound/Exam-v0", exam=str(root), row=row.row)
        obs, info = env.reset()
        assert not ANSWER & set(info) and info["instruction"] == row.instruction
        ee, objects = [info["ee"].tolist()], {k: [list(v)] for k, v in info["objects"].items()}
        for _ in range(min(row.max_steps, 60)):
            action = reach_the_named_object(row.instruction, scene, geometry, obs["observation.state"])
            obs, _, _, truncated, info = env.step(action)
            assert not ANSWER & set(info)
            ee.append(info["ee"].tolist())
            for k, v in info["objects"].items():
                objects[k].append(list(v))
            if truncated:
                break
        env.close()
        logs.append({"row": row.row, "ee": ee, "objects": json.dumps(objects), "error": None})
    pd.DataFrame(logs).to_parquet(tmp_path / "rollouts.parquet")
    scored = subprocess.run(
        [sys.executable, "-m", "eval.score", f"exam={root}", f"logs={tmp_path / 'rollouts.parquet'}", f"out={tmp_path}"],
        capture_output=True,
        text=True,
    )
    assert scored.returncode == 0, scored.stderr
    faces = json.loads((tmp_path / "report.json").read_text())["faces"]
    assert faces["obeyed_name"]["rate"] >= 0.8 and faces["true_target"]["rate"] <= 0.1  # it reads the instruction
    assert faces["nonsense"]["k"] == 0 and faces["task"]["k"] == 0  # it never lifts anything


LAB_SCRIPT = """
import gymnasium as gym
{first}
env = gym.make("deconfound_exam:deconfound/Exam-v0", exam={exam!r}, row=0)
obs, info = env.reset()
print(info["instruction"], sorted(obs))
"""


def test_the_env_is_made_from_a_lab_folder_whose_own_packages_share_our_names(tmp_path: Path) -> None:
    root = make_dataset(tmp_path / "exam", "n=1", "split=exam", "image_size=32")
    lab = tmp_path / "lab"
    for package in ("eval", "core"):  # a lab's own packages, first on sys.path when it runs from its folder
        (lab / package).mkdir(parents=True)
        (lab / package / "__init__.py").write_text("LAB = True\n")

    def run(first: str) -> subprocess.CompletedProcess[str]:
        script = LAB_SCRIPT.format(first=first, exam=str(root))
        return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=lab)

    made = run("")
    assert made.returncode == 0, made.stderr[-2000:]
    instruction = pd.read_parquet(root / "trials.parquet").set_index("row").loc[0, "instruction"]
    assert (
        made.stdout.strip()
        == f"{instruction} {sorted(['observation.images.agentview', 'observation.images.wrist', 'observation.state'])}"
    )
    clash = run("import eval")  # the lab's own eval imported first: one line naming both, not a mixed-up import
    assert clash.returncode != 0
    assert f"a package named 'eval' ({lab / 'eval' / '__init__.py'}) is already imported" in clash.stderr.strip().splitlines()[-1]
