"""Exams and the counterfactual battery: held-out scenes, a self-contained format, reference
policies that rank as the instrument demands, one scorer for online and offline logs, and
clear failures for bad exams, bad actions and unreachable servers."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

from core import parquet
from core.exam import FACES, read
from core.spec import Setup
from eval.policies import Context, PolicyError
from eval.policies.registry import make, names, register
from eval.scoring.battery import take
from eval.sims.rollout import Runner
from gen.planning.plan import plan
from gen.products import scenes
from helpers import make_dataset, rows_of
from referents import registry


@pytest.fixture(scope="module")
def small_exam(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return make_dataset(
        tmp_path_factory.mktemp("exam") / "object-exam", "referent=object", "n=6", "split=exam", "seed=7", "image_size=64"
    )


def test_exam_scenes_never_occur_in_training(small_exam: Path, object_dataset: Path) -> None:
    exam_hashes = set(parquet.read(small_exam / "answers.parquet")["scene_hash"])
    assert exam_hashes.isdisjoint(set(scenes.read(object_dataset)["scene_hash"]))
    ref = registry.load("object")
    train = {s.scene_hash for s in plan(ref, 300, seed=7, setup=Setup())}
    held_out = {s.scene_hash for s in plan(ref, 300, seed=7, setup=Setup(), split="exam")}
    assert train.isdisjoint(held_out)


def test_exam_format_reads_without_our_code(small_exam: Path) -> None:
    meta = json.loads((small_exam / "exam.json").read_text())
    public, answers = parquet.read(small_exam / "trials.parquet"), parquet.read(small_exam / "answers.parquet")
    assert not {"face", "target", "program", "spec", "alternatives", "original_target"} & set(public.columns)
    trials = public.merge(answers, on="row")
    assert meta["format"] == "deconfound-exam" and meta["version"] == 2
    assert {"scoring", "geometry", "faces", "observation", "audit"} <= set(meta)
    assert meta["trials"] == 6 and meta["rollouts"] == len(trials)
    for _, t in trials.groupby("trial"):
        alternatives = json.loads(t["alternatives"].iloc[0])
        switched = list(t["face"]).count("switch")  # one a trial, none where the hand starts within reach
        assert switched <= 1
        faces = ["task", "occ", "nonsense"] + ["swap"] * (len(alternatives) - 1) + ["switch"] * switched
        assert sorted(t["face"]) == sorted(faces)
        swaps = t[t.face == "swap"]
        assert {(r.target, r.program) for r in swaps.itertuples()} == {(a["target"], a["program"]) for a in alternatives[1:]}
        assert (t[t.face == "nonsense"].instruction == "xxx").all() and t[t.face == "occ"].occluded.all()
        assert len(set(t["initial_state"].map(tuple))) == 1 and len(t["initial_state"].iloc[0]) > 50


def test_reference_policies_rank_as_the_instrument_demands(tmp_path_factory: pytest.TempPathFactory) -> None:
    # the switch face has its own test (tests/sim/test_new_faces.py); these policies read no frames: 32 px
    args = ("referent=object", "n=40", "split=exam", "seed=3", "switches=0", "image_size=32")
    exam = read(make_dataset(tmp_path_factory.mktemp("exam40") / "object-exam", *args))
    out = tmp_path_factory.mktemp("runs")
    # each policy takes the rows of the faces read of it below; `nothing` runs every row to its horizon: a
    # few trials show its zeros (and its take measures the shortcut baseline on them)
    rows = {
        "position": rows_of(exam, ["swap"]),
        "oracle": rows_of(exam, ["task", "occ", "swap"], 20),  # its >= 95% on half the trials: ~70 rollouts
        "nothing": rows_of(exam, FACES, 5),
    }
    reports = {p: take(exam, rows[p], make(p), out / p, policy_name=p, baseline=p == "nothing")[0] for p in rows}
    oracle, position, nothing = reports["oracle"]["faces"], reports["position"]["faces"], reports["nothing"]["faces"]
    assert oracle["obeyed_name"]["rate"] >= 0.95 and oracle["true_target"]["rate"] <= 0.05
    assert oracle["task"]["rate"] >= 0.95
    # the oracle reads the spec, not the cameras: blanking them cannot hurt it (docs/EXAMS.md: what occ proves)
    assert oracle["occ"]["rate"] == oracle["task"]["rate"]
    lo, hi = position["obeyed_name"]["ci"]
    assert lo <= position["obeyed_name"]["chance"] <= hi
    assert all(f["k"] == 0 for f in nothing.values())
    assert all(r["init_value"]["trusted"] for r in reports.values())
    assert reports["oracle"]["distances"]["median_to_named"] < 0.02 < reports["oracle"]["distances"]["median_to_original"]


def test_offline_scorer_gives_the_identical_report(small_exam: Path, tmp_path: Path) -> None:
    exam = read(small_exam)
    take(exam, exam.trials, make("position"), tmp_path / "online")
    offline = tmp_path / "offline"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "eval.score",
            f"exam={small_exam}",
            f"logs={tmp_path / 'online/rollouts.parquet'}",
            f"out={offline}",
        ],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, result.stderr
    assert (offline / "report.json").read_bytes() == (tmp_path / "online/report.json").read_bytes()
    assert (offline / "report.html").stat().st_size > 10_000  # three embedded plots


class Broken:
    """A policy that misbehaves on purpose: NaN on even rows, a wrong shape on odd ones."""

    name = "broken"
    needs_images = True

    def reset(self, context: Context) -> None:
        self.row = context.seed

    def act(self, observation: dict) -> np.ndarray:
        assert observation["observation.images.agentview"].shape == (64, 64, 3)
        return np.full(8, np.nan) if self.row % 2 == 0 else np.zeros(3)


def test_bad_actions_fail_their_trial_and_the_run_goes_on(small_exam: Path, tmp_path: Path) -> None:
    exam = read(small_exam)
    rows = exam.trials.head(4)
    report, _ = take(exam, rows, Broken(), tmp_path)
    errors = {e["row"]: e["error"] for e in report["errors"]}
    assert len(errors) == 4
    assert "NaN" in errors[0] and "shape (3,)" in errors[1]
    assert report["faces"]["task"]["k"] == 0
    occluded = exam.trials[exam.trials.face == "occ"].iloc[0]
    assert Runner(make("nothing")).run(occluded).error is None


def test_policies_are_made_by_registered_name() -> None:
    """eval registers its own policies; train's `ckpt` comes from its entry point, so eval never
    imports train. A name with a missing or surplus argument is one clear line."""
    assert names()[:6] == ["oracle", "position", "named_place", "nothing", "random", "remote:HOST:PORT"]
    assert "ckpt:PATH" in names()
    for name, needle in [
        ("telepathy", "unknown policy 'telepathy'; registered: oracle, position, named_place, nothing, random, remote:HOST:PORT"),
        ("ckpt", "policy ckpt needs an argument: ckpt:PATH"),
        ("oracle:x", "policy oracle takes no argument"),
        ("remote:nohost", "must be HOST:PORT"),
        ("ckpt:/nowhere", "no checkpoint at /nowhere"),
    ]:
        with pytest.raises(PolicyError) as caught:
            make(name)
        assert needle in str(caught.value) and "\n" not in str(caught.value)
    register("broken", Broken)
    assert isinstance(make("broken"), Broken) and "broken" in names()


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "eval", *args], capture_output=True, text=True)


def test_bad_exams_and_servers_get_one_line(small_exam: Path, tmp_path: Path) -> None:
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "exam.json").write_text("{not json")
    future = tmp_path / "future"
    future.mkdir()
    meta = json.loads((small_exam / "exam.json").read_text())
    (future / "exam.json").write_text(json.dumps({**meta, "version": 99}))
    for args, needle in [
        ((f"exam={broken}", "policy=oracle"), "exam.json is corrupt"),
        ((f"exam={future}", "policy=oracle"), "version 99 is not supported"),
        ((f"exam={tmp_path}", "policy=oracle"), "no exam.json"),
        ((f"exam={small_exam}", "policy=remote:127.0.0.1:9"), "unreachable"),
        ((f"exam={small_exam}", "policy=telepathy"), "unknown policy"),
    ]:
        result = _cli(*args)
        assert result.returncode == 2 and len(result.stderr.strip().splitlines()) == 1 and needle in result.stderr, result.stderr


def test_remote_policy_over_the_openpi_protocol(small_exam: Path, tmp_path: Path) -> None:
    from openpi_client import msgpack_numpy
    from websockets.sync.server import serve

    seen: list[dict] = []

    def handler(ws) -> None:  # noqa: ANN001
        ws.send(msgpack_numpy.Packer().pack({"server": "test"}))
        for message in ws:
            obs = msgpack_numpy.unpackb(message)
            seen.append(obs)
            home = np.array([0.0, 0.19634954, 0.0, -2.61799388, 0.0, 2.94159265, 0.78539816, -1.0], np.float32)
            ws.send(msgpack_numpy.Packer().pack({"actions": np.tile(home, (10, 1))}))

    with serve(handler, "127.0.0.1", 0) as server:
        port = server.socket.getsockname()[1]
        threading.Thread(target=server.serve_forever, daemon=True).start()
        exam = read(small_exam)
        report, _ = take(exam, exam.trials.head(3), make(f"remote:127.0.0.1:{port}"), tmp_path)
        server.shutdown()
    assert not report["errors"] and report["faces"]["task"]["k"] == 0
    assert seen[0]["prompt"] == exam.trials.iloc[0]["instruction"]
    assert seen[0]["observation.images.wrist"].shape == (64, 64, 3) and seen[0]["observation.state"].shape == (16,)


def test_gym_environment_replays_a_trial(small_exam: Path) -> None:
    import gymnasium as gym

    exam = read(small_exam)
    row = exam.trials[(exam.trials.trial == 1) & (exam.trials.face == "swap")].iloc[0]
    oracle = make("oracle")
    oracle.reset(Context(exam.spec(row), row["instruction"], row["target"], row["program"], 0))
    env = gym.make("deconfound_exam:deconfound/Exam-v0", exam=small_exam, row=int(row["row"]), disable_env_checker=True)
    obs, info = env.reset()
    assert info["instruction"] == row["instruction"] and obs["observation.images.agentview"].shape == (64, 64, 3)
    reward = 0.0
    while (action := oracle.act({})) is not None:
        obs, reward, terminated, truncated, info = env.step(action)
    assert reward == 1.0 and info["achieved"]
    env.close()


def test_a_closed_environments_renderer_serves_the_next_of_its_scene(small_exam: Path) -> None:
    """A loop making an environment per row: after close() the next one takes over the renderer and
    draws the same frames as one started anew; two open at once each have their own."""
    from eval.env import ExamEnv

    def frames(env: ExamEnv) -> dict[str, np.ndarray]:
        env.reset()
        obs = env.step(np.zeros(env.action_space.shape, np.float32))[0]
        return {k: v.copy() for k, v in obs.items() if k.startswith("observation.images")}

    first = ExamEnv(small_exam, row=1)
    shown, cameras = frames(first), first.cameras
    first.close()
    second, third = ExamEnv(small_exam, row=1), ExamEnv(small_exam, row=1)
    assert second.cameras is cameras and third.cameras is not cameras
    again, anew = frames(second), frames(third)
    assert all(np.array_equal(shown[k], again[k]) and np.array_equal(shown[k], anew[k]) for k in shown)
    second.close()
    third.close()


@pytest.mark.parametrize("row", [999, -1])
def test_the_gym_environment_names_the_rows_an_exam_has(small_exam: Path, row: int) -> None:
    import gymnasium as gym

    last = int(read(small_exam).trials["row"].max())
    with pytest.raises(ValueError, match=rf"^the exam has rows 0..{last}, not row={row}$"):
        gym.make("deconfound_exam:deconfound/Exam-v0", exam=small_exam, row=row, disable_env_checker=True)


def test_a_verb_exams_horizon_does_not_tell_the_program(tmp_path: Path) -> None:
    """Every row of a trial runs under one horizon, long enough for the longest of its programs:
    the oracle's demonstration of any row's ask fits in it with the usual margin (a switch row's
    horizon counts from its switch, and the switch row says it is one)."""
    from core.spec import EpisodeSpec
    from gen.products.exam import HORIZON_FACTOR, HORIZON_SLACK
    from oracle.episode import demonstrate
    from oracle.ik import ArmIK
    from oracle.scene import scene_for
    from referents.registry import demo_of

    exam = read(make_dataset(tmp_path / "verb-exam", "referent=verb", "n=4", "split=exam", "seed=2", "image_size=32"))
    assert (exam.trials[exam.trials["face"] != "switch"].groupby("trial")["max_steps"].nunique() == 1).all()
    spec = EpisodeSpec.from_json(exam.trials["spec"].iloc[0])
    scene, ik = scene_for(spec.assets), ArmIK(np.asarray(spec.setup.robot_home))
    for _, row in exam.trials[exam.trials["face"].isin(["task", "swap"])].iterrows():
        spec = EpisodeSpec.from_json(row["spec"])
        asked = dataclasses.replace(spec, target=row["target"], task=dataclasses.replace(spec.task, program=row["program"]))
        steps = len(demonstrate(scene, ik, asked, demo_of("verb")).actions)
        assert HORIZON_FACTOR * steps + HORIZON_SLACK <= row["max_steps"] + 1, (row["trial"], row["program"], steps)
