"""A training set whose episodes change course (`switched=`, issue 52): lerobot's own loader gives
each frame the instruction it was shown and its lerobot-train trains on them, the second
instruction is achieved, and the set
regenerates bit for bit from its specs (gen.verify), and training aims each frame at what its
instruction names (train/data.py `aim`) and can draw the frames after a switch as often as asked
(`switched_share`)."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from ledataset.datasets.lerobot_dataset import LeRobotDataset

from core.profiles import PROFILES
from core.spec import EpisodeSpec
from gen.products import scenes
from gen.verify import verify
from helpers import ROOT, lerobot_train, make_dataset
from train import data


def test_switched_episodes_change_task_where_the_record_says(tmp_path: Path) -> None:
    root = make_dataset(tmp_path / "switched", "referent=object", "n=4", "switched=0.5", "image_size=32", "workers=1")
    records = scenes.read(root).sort_values("episode_index")
    ds = LeRobotDataset("local/switched", root=root)
    episodes, seen = ds.meta.episodes, 0
    for ep, instruction, switch, spec in zip(records.episode_index, records.instruction, records.switch, records.spec):
        start, end = episodes[ep]["dataset_from_index"], episodes[ep]["dataset_to_index"]
        assert ds[start]["task"] == instruction
        if not isinstance(switch, str):
            assert ds[end - 1]["task"] == instruction and EpisodeSpec.from_json(spec).switch is None
            continue
        then, seen = json.loads(switch), seen + 1
        assert 0 < then["step"] < end - start
        assert ds[start + then["step"] - 1]["task"] == instruction and ds[start + then["step"]]["task"] == then["instruction"]
        assert ds[end - 1]["task"] == then["instruction"] != instruction
        assert EpisodeSpec.from_json(spec).after_switch().target == then["target"]
    assert seen == 2
    assert verify(root, 4) == [0, 1, 2, 3]  # each demo, re-run, changes course where it did and achieves the second ask
    tiny = {"dim_model": 64, "dim_feedforward": 128, "chunk_size": 10, "n_action_steps": 10}
    act = lerobot_train(tmp_path / "act", root, type="act", pretrained_backbone_weights="null", **tiny)
    assert (act / "model.safetensors").is_file()  # upstream lerobot-train trains on frames of either instruction
    frames = data.load(root)
    moved = frames.aim != frames.episode
    for ep, switch, scene in zip(records.episode_index, records.switch, records.scene):
        own = frames.episode == ep
        if not isinstance(switch, str):
            assert not moved[own].any()
            continue
        then = json.loads(switch)
        assert np.flatnonzero(moved & own).tolist() == list(range(frames.starts[ep] + then["step"], frames.ends[ep]))
        second = next(o["pos"] for o in json.loads(scene)["objects"] if o["id"] == then["target"])
        np.testing.assert_allclose(frames.target[frames.aim[frames.ends[ep] - 1]], second, atol=1e-6)
    group, chances = data.after_switch(frames, None, None, 0.8)  # their frames after the switch: 80% of each batch
    drawn = data.sample(frames, np.random.default_rng(0), 8000, True, group, chances)
    assert abs(np.mean(moved[drawn]) - 0.8) < 0.02 and np.mean(moved) < 0.6
    group, chances = data.after_switch(frames, None, None, 0.8, first=3)  # only the first 3 frames from each switch
    turning = np.zeros(len(frames), bool)
    for ep, switch in zip(records.episode_index, records.switch):
        if isinstance(switch, str):
            turning[frames.starts[ep] + json.loads(switch)["step"] + np.arange(3)] = True
    assert np.array_equal(group == group.max(), turning)
    drawn = data.sample(frames, np.random.default_rng(0), 8000, True, group, chances)
    assert abs(np.mean(turning[drawn]) - 0.8) < 0.02
    group, chances = data.after_switch(frames, None, None, 0.8, first=3, before=2)  # and the 2 frames before, halves
    leading = np.zeros(len(frames), bool)
    for ep, switch in zip(records.episode_index, records.switch):
        if isinstance(switch, str):
            step = json.loads(switch)["step"]
            leading[frames.starts[ep] + np.arange(max(0, step - 2), step)] = True  # never the episode before
    assert np.array_equal(group == group.max(), leading) and np.array_equal(group == group.max() - 1, turning)
    drawn = data.sample(frames, np.random.default_rng(0), 8000, True, group, chances)
    assert abs(np.mean(turning[drawn]) - 0.4) < 0.02 and abs(np.mean(leading[drawn]) - 0.4) < 0.02
    group, chances = data.after_switch(frames, None, None, 0.8, first=3, stay=True)  # or unswitched frames, as near
    stays = ~np.isin(frames.episode, [ep for ep, sw in zip(records.episode_index, records.switch) if isinstance(sw, str)])
    stays &= data.until_grasp(frames)  # an unswitched episode's frames before its grasp
    assert np.array_equal(group == 1, turning) and np.array_equal(group > 1, stays)
    drawn = data.sample(frames, np.random.default_rng(0), 8000, True, group, chances)
    assert abs(np.mean(turning[drawn]) - 0.4) < 0.02 and abs(np.mean(stays[drawn]) - 0.4) < 0.02
    reach = np.linalg.norm(frames.state[:, PROFILES[frames.profile].hand] - frames.target[frames.episode], axis=1)
    bins, at = reach // data.REACH_BIN, data.switch_frames(frames)
    held = np.unique(bins[stays])
    nearest = {held[np.abs(held - b).argmin()] for b in bins[at[at < len(frames)]]}
    assert set(bins[drawn[stays[drawn]]]) == nearest  # as near their target as the switches' hands are to theirs
    unswitched = replace(frames, aim=frames.episode)
    with pytest.raises(data.DatasetError, match="switched_share=0.8 needs switched episodes"):
        data.after_switch(unswitched, None, None, 0.8)
    ckpt = tmp_path / "ckpt"  # scripts/switch_probe.py: a checkpoint's turn at each switch of the set
    trained = subprocess.run([sys.executable, "-m", "train", f"dataset={root}", "steps=1", "threads=1", f"out={ckpt}"],
                             capture_output=True, text=True)  # fmt: skip
    assert trained.returncode == 0, trained.stderr[-2000:]
    probe = [sys.executable, str(ROOT / "scripts" / "switch_probe.py"), f"dataset={root}"]
    probed = subprocess.run([*probe, f"policies=[ckpt:{ckpt}]"], capture_output=True, text=True)
    assert probed.returncode == 0, probed.stderr[-2000:]
    rows = [line for line in probed.stdout.splitlines() if line.startswith(f"| ckpt:{ckpt} |")]
    assert "2 switched episodes" in probed.stdout and [r.split("|")[2].strip() for r in rows] == ["switch+0", "switch+5"]
    refused = subprocess.run([*probe, f"policies=[{ckpt}]"], capture_output=True, text=True)
    assert refused.returncode == 2 and len(refused.stderr.strip().splitlines()) == 1, refused.stderr
    turned = tmp_path / "turns"  # train/turns.py: the oracle's turn from a policy's own state (the oracle policy's here)
    command = [sys.executable, "-m", "train.turns", "policy=oracle", "later=[0]", "after=[0,1]"]
    turns = [*command, f"out={turned}"]
    made = subprocess.run([*turns, f"dataset={root}"], capture_output=True, text=True)
    assert made.returncode == 0 and "wrote 4 turns from 2 switched scenes" in made.stdout, made.stderr[-2000:]
    records, ds = scenes.read(turned).sort_values("episode_index"), LeRobotDataset("local/turns", root=turned)
    for ep, instruction, switch in zip(records.episode_index, records.instruction, records.switch):
        start, end = ds.meta.episodes[ep]["dataset_from_index"], ds.meta.episodes[ep]["dataset_to_index"]
        if ep % 2:  # the policy went on a chunk under the second name, the oracle took over: that name throughout
            assert not isinstance(switch, str) and instruction == json.loads(records.switch.iloc[ep - 1])["instruction"]
            assert ds[start]["task"] == ds[end - 1]["task"] == instruction
            continue
        then = json.loads(switch)
        assert then["step"] == 1 and ds[start]["task"] == instruction and ds[start + 1]["task"] == then["instruction"]
    union = data.load([str(root), str(turned)])  # a union's switches are each part's, where they are
    assert np.array_equal(data.after_switches(union), np.concatenate([moved, data.after_switches(data.load(turned))]))
    refused = subprocess.run([*turns, f"dataset={tmp_path / 'none'}"], capture_output=True, text=True)
    assert refused.returncode == 2 and "is no finished generated dataset" in refused.stderr, refused.stderr
    again = subprocess.run([*turns, f"dataset={root}", "resume=true"], capture_output=True, text=True)
    assert again.returncode == 0 and "already complete (4 episodes, same options)" in again.stdout, again.stderr[-2000:]
    mine = tmp_path / "mine"  # a folder of the user's: never written into, nor replaced
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    for extra in ([], ["overwrite=true"]):
        kept = subprocess.run([*command, f"out={mine}", f"dataset={root}", *extra], capture_output=True, text=True)
        assert kept.returncode == 2 and len(kept.stderr.strip().splitlines()) == 1, kept.stderr
    assert [p.name for p in mine.iterdir()] == ["notes.txt"]
